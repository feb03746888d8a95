"""Awaitable agent commands for async missions: each queues the matching Action.

``await agent.move(path)`` queues a MoveAction and resolves when it ends: it returns the
finished action, raises ActionFailedError (with ``.action`` and its ``error_message``) when it
FAILED, and ActionCancelledError when something outside the mission cancelled it. Cancelling
the mission (a task group, a sim-time timeout, a race it lost) cancels the action: a queued one
is dropped, a running one stops the robot in that step.
"""

from __future__ import annotations

from collections.abc import Awaitable, Generator
from typing import TYPE_CHECKING, Any

from fleet_async.core.actions.action import Action, MoveAction, WaitAction
from fleet_async.core.actions.arm_actions import JointAction, PoseAction
from fleet_async.core.actions.pick_drop import DropAction, PickAction
from fleet_async.core.base.types import ActionStatus
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.waypoints import Path

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.missions.mission_api import MissionRuntime

__all__ = ["ActionHandle", "AgentMissionApi"]


class ActionHandle:
    """A queued action: ``await handle`` waits for it (returning it, or raising if it failed
    or was cancelled); ``cancel()`` cancels it; ``status``, ``phase`` and ``progress`` watch it.
    """

    def __init__(self, agent: Agent, action: Action) -> None:
        self.agent = agent
        self.action = action

    @property
    def status(self) -> ActionStatus:
        """The action's status."""
        return self.action.status

    @property
    def done(self) -> bool:
        """Whether the action has ended."""
        return self.action.is_complete()

    @property
    def phase(self) -> Any:
        """The pick / drop phase, or None for actions without phases."""
        return getattr(self.action, "phase", None)

    @property
    def progress(self) -> float:
        """Rough completion in [0, 1]: waypoints reached for moves, time spent for waits."""
        action = self.action
        if action.is_complete():
            return 1.0
        if action.start_time is None:
            return 0.0
        if isinstance(action, WaitAction):
            sim = self.agent.sim_core
            if action.duration <= 0 or sim is None:
                return 0.0
            return min(1.0, (sim.sim_time - action.start_time) / action.duration)
        if isinstance(action, MoveAction):
            total = len(action.path)
            return min(1.0, self.agent.current_waypoint_index / total) if total else 0.0
        return 0.0

    def cancel(self) -> None:
        """Cancel the action (a queued one is dropped, a running one stops its robot now)."""
        self.action.cancel()

    def __await__(self) -> Generator[Any, None, Action]:
        sim = self.agent.sim_core
        runtime = None if sim is None else sim.mission_runtime
        if runtime is None:
            raise RuntimeError("awaiting an action needs a running mission (fleet_async.run)")
        return self._wait(runtime).__await__()

    async def _wait(self, runtime: MissionRuntime) -> Action:
        return await runtime.wait_action(self.action, "await handle")


class AgentMissionApi:
    """Mixin for Agent: ``await agent.move(...)``, ``pick``, ``drop``, ``wait``, ``charge``,
    ``move_joints``, ``reach_pose``."""

    def _mission_runtime(self, what: str) -> MissionRuntime:
        sim = getattr(self, "sim_core", None)
        runtime = None if sim is None else sim.mission_runtime
        if runtime is None:
            raise RuntimeError(
                f"{what} needs a running mission: start missions with fleet_async.run(sim, main)"
            )
        return runtime

    def submit(self, action: Action) -> ActionHandle:
        """Queue ``action`` now and return a handle to await, cancel or watch it.

        ``await agent.submit(action)`` waits for it to end, like the other commands.
        """
        self._mission_runtime("agent.submit")
        agent: Agent = self  # type: ignore[assignment]  # this mixin is only used by Agent
        agent.add_action(action)
        return ActionHandle(agent, action)

    def _run(self, action: Action, what: str) -> Awaitable[Action]:
        """Queue ``action`` and return the wait for it (what ``await self.submit(action)``
        does, without building a handle); the commands await it at once."""
        runtime = self._mission_runtime(what)
        agent: Agent = self  # type: ignore[assignment]  # this mixin is only used by Agent
        agent.add_action(action)
        return runtime.wait_action(action, what)

    async def move(self, path: Path | Pose | list[Pose], **options: Any) -> Action:
        """Follow ``path``; options as MoveAction (auto_approach, direction, ...)."""
        if not isinstance(path, (Path, Pose)):
            path = Path(list(path))
        action = MoveAction(path=path, **options)  # type: ignore[arg-type]  # takes a Pose too
        return await self._run(action, "agent.move")

    async def pick(self, target: Any = None, **options: Any) -> Action:
        """Pick ``target`` (a SimObject or body id), or pass PickAction options such as
        ``target_position`` and ``search_radius``."""
        if target is not None:
            options["target_object_id"] = target
        return await self._run(PickAction(**options), "agent.pick")

    async def drop(self, drop_pose: Pose, **options: Any) -> Action:
        """Drop what is carried at ``drop_pose`` (DropAction options)."""
        return await self._run(DropAction(drop_pose=drop_pose, **options), "agent.drop")

    async def wait(self, duration: float, action_type: str = "idle") -> Action:
        """Stand still for ``duration`` sim seconds as a queued WaitAction."""
        return await self._run(WaitAction(duration=duration, action_type=action_type), "agent.wait")

    async def charge(self, duration: float) -> Action:
        """Charge the battery for ``duration`` sim seconds."""
        return await self.wait(duration, action_type="charge")

    async def move_joints(self, targets: Any, **options: Any) -> Action:
        """Move joints to ``targets`` (a list, or {joint name: position}) as a JointAction;
        options: ``max_force``, ``tolerance``."""
        return await self._run(
            JointAction(target_joint_positions=targets, **options), "agent.move_joints"
        )

    async def reach_pose(self, position: Any, orientation: Any = None, **options: Any) -> Action:
        """Bring the end effector to ``position`` ([x, y, z], world frame) and optionally
        ``orientation`` ([qx, qy, qz, qw]) through IK, as a PoseAction (raises
        ActionFailedError when it is out of reach); options: ``end_effector_link``,
        ``max_force``, ``tolerance``."""
        return await self._run(
            PoseAction(target_position=position, target_orientation=orientation, **options),
            "agent.reach_pose",
        )
