"""Awaitable agent commands for async missions: each queues the matching Action.

``await agent.move(path)`` queues a MoveAction and resolves when it ends: it returns the
finished action, raises ActionFailedError (with ``.action`` and its ``error_message``) when it
FAILED, and ActionCancelledError when something outside the mission cancelled it. Cancelling
the mission (a task group, a sim-time timeout, a race it lost) cancels the action: a queued one
is dropped, a running one stops the robot in that step.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from fleet_async.core.action import Action, MoveAction, WaitAction
from fleet_async.core.geometry import Path, Pose
from fleet_async.core.pick_drop import DropAction, PickAction

if TYPE_CHECKING:
    from fleet_async.core.agent import Agent
    from fleet_async.core.mission_api import MissionRuntime

__all__ = ["AgentMissionApi"]


class AgentMissionApi:
    """Mixin for Agent: ``await agent.move(...)``, ``pick``, ``drop``, ``wait``, ``charge``."""

    def _mission_runtime(self, what: str) -> MissionRuntime:
        sim = getattr(self, "sim_core", None)
        runtime = None if sim is None else sim.mission_runtime
        if runtime is None:
            raise RuntimeError(
                f"{what} needs a running mission: start missions with fleet_async.run(sim, main)"
            )
        return runtime

    async def submit(self, action: Action) -> Action:
        """Queue any action and wait for it to end."""
        agent: Agent = self  # type: ignore[assignment]
        return await self._mission_runtime("agent.submit").await_action(
            agent, action, "agent.submit"
        )

    async def move(self, path: Path | Pose | list[Pose], **options: Any) -> Action:
        """Follow ``path``; options as MoveAction (auto_approach, direction, ...)."""
        if isinstance(path, Pose):
            path = Path([path])
        elif not isinstance(path, Path):
            path = Path(list(path))
        return await self.submit(MoveAction(path=path, **options))

    async def pick(self, target: Any = None, **options: Any) -> Action:
        """Pick ``target`` (a SimObject or body id), or pass PickAction options such as
        ``target_position`` and ``search_radius``."""
        if target is not None:
            options["target_object_id"] = target
        return await self.submit(PickAction(**options))

    async def drop(self, drop_pose: Pose, **options: Any) -> Action:
        """Drop what is carried at ``drop_pose`` (DropAction options)."""
        return await self.submit(DropAction(drop_pose=drop_pose, **options))

    async def wait(self, duration: float, action_type: str = "idle") -> Action:
        """Stand still for ``duration`` sim seconds as a queued WaitAction."""
        return await self.submit(WaitAction(duration=duration, action_type=action_type))

    async def charge(self, duration: float) -> Action:
        """Charge the battery for ``duration`` sim seconds."""
        return await self.wait(duration, action_type="charge")
