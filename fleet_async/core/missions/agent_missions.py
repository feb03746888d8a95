"""Agent commands for async missions: each queues the matching Action and returns its event.

``agent.move(path)`` queues a MoveAction at once and returns an event for it (the runtime's
``ActionWait``): ``await`` it to wait for the end; it returns the finished action, raises
ActionFailedError (with ``.action`` and its ``error_message``) when it FAILED, and
ActionCancelledError when something outside the mission cancelled it. The event is also a
handle (``cancel()``, ``status``, ``phase``, ``progress``) and composes with ``sim.any_of``.
Cancelling a mission that awaits it (a task group, a sim-time timeout, a race it lost, an
interrupt) cancels the action: a queued one is dropped, a running one stops the robot in that
step.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from fleet_async.core.actions.action import Action, MoveAction, WaitAction
from fleet_async.core.actions.arm_actions import JointAction, PoseAction
from fleet_async.core.actions.pick_drop import DropAction, PickAction
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.waypoints import Path
from fleet_async.core.missions.errors import ExternallyDrivenError, NoMissionRuntimeError
from fleet_async.core.routes.api import graph_of
from fleet_async.core.routes.follow import route_to_node

if TYPE_CHECKING:
    from fleet_async.core.missions.host import MissionAgent
    from fleet_async.core.missions.mission_api import MissionRuntime

__all__ = ["AgentMissionApi"]


class AgentMissionApi:
    """Mixin for Agent: ``await agent.move(...)``, ``pick``, ``drop``, ``wait``, ``charge``,
    ``move_joints``, ``reach_pose``, ``submit``. Each queues its action when called and
    returns an event for it."""

    external_driver: str | None = None
    """Who drives this agent from outside the simulation (a served fleet's master), or None.

    While set, mission commands to the agent are refused: two drivers would fight over its
    action queue. Set by a fleet interface (``fleet_async.interfaces``) when it serves the agent.
    """

    def _mission_runtime(self, what: str) -> MissionRuntime:
        agent: MissionAgent = self  # type: ignore[assignment]  # mixed into Agent, a MissionAgent
        agent.check_not_removed(what)  # "needs a running mission" would mislead
        if self.external_driver is not None:
            raise ExternallyDrivenError(
                f"{what}: {agent.name!r} is driven by {self.external_driver}; a mission cannot "
                "command it (leave it out of the served robots to drive it from a mission)"
            )
        sim = agent.sim_core
        runtime = None if sim is None else sim.mission_runtime
        if runtime is None:
            raise NoMissionRuntimeError(
                f"{what} needs a running mission: start missions with fleet_async.run(sim, main)"
            )
        return runtime

    def submit(self, action: Action) -> Any:
        """Queue ``action`` now and return its event: ``await`` it to wait for the end,
        ``cancel()`` it, or watch ``status``, ``phase`` and ``progress``."""
        runtime = self._mission_runtime("agent.submit")
        agent: MissionAgent = self  # type: ignore[assignment]  # mixed into Agent, a MissionAgent
        action.awaited = True  # e.g. a move on a fixed base fails rather than being skipped
        agent.add_action(action)
        return runtime.wait_action(agent, action)

    def move(self, path: Path | Pose | list[Pose], **options: Any) -> Any:
        """Follow ``path``; options as MoveAction (auto_approach, direction, ...)."""
        if not isinstance(path, (Path, Pose, list, tuple)) and isinstance(path, Iterable):
            path = list(path)  # MoveAction names what it got when this is not Poses
        action = MoveAction(path=path, **options)  # type: ignore[arg-type]  # takes a Pose too
        return self.submit(action)

    def go_to_node(self, node_id: str) -> Any:
        """Drive the quickest route of the simulation's route graph from the nearest node to
        ``node_id``, each edge at its speed limit (``routes/follow.py``)."""
        return self.submit(route_to_node(self, graph_of(self), node_id))

    def pick(self, target: Any = None, **options: Any) -> Any:
        """Pick ``target`` (a SimObject or body id), or pass PickAction options such as
        ``target_position`` and ``search_radius``."""
        if target is not None:
            options["target_object_id"] = target
        return self.submit(PickAction(**options))

    def drop(self, drop_pose: Pose, **options: Any) -> Any:
        """Drop what is carried at ``drop_pose`` (DropAction options)."""
        return self.submit(DropAction(drop_pose=drop_pose, **options))

    def wait(self, duration: float, action_type: str = "idle") -> Any:
        """Stand still for ``duration`` sim seconds as a queued WaitAction."""
        return self.submit(WaitAction(duration=duration, action_type=action_type))

    def charge(self, duration: float) -> Any:
        """Charge the battery for ``duration`` sim seconds.

        Raises:
            ValueError: if the agent has no battery (charging would only wait), saying how to
                give it one.
        """
        agent: MissionAgent = self  # type: ignore[assignment]  # mixed into Agent, a MissionAgent
        if agent.battery_plugin is None:
            raise ValueError(
                f"agent.charge: {agent!r} has no battery, so charging would only wait. Give it "
                "one: in a scenario, 'plugins: [{type: battery, config: {initial_soc: 0.5}}]' "
                "on its entity; in Python, agent.add_plugin(BatteryPlugin(agent, "
                "{'initial_soc': 0.5})) or AgentSpawnParams(..., plugins=[{'type': "
                "'battery'}]). To wait without charging, use agent.wait(duration)"
            )
        return self.wait(duration, action_type="charge")

    def move_joints(self, targets: Any, **options: Any) -> Any:
        """Move joints to ``targets`` (a list, or {joint name: position}) as a JointAction;
        options: ``max_force``, ``tolerance``."""
        return self.submit(JointAction(target_joint_positions=targets, **options))

    def reach_pose(self, position: Any, orientation: Any = None, **options: Any) -> Any:
        """Bring the end effector to ``position`` ([x, y, z], world frame) and optionally
        ``orientation`` ([qx, qy, qz, qw]) through IK, as a PoseAction (raises
        ActionFailedError when it is out of reach); options: ``end_effector_link``,
        ``max_force``, ``tolerance``."""
        return self.submit(
            PoseAction(target_position=position, target_orientation=orientation, **options)
        )
