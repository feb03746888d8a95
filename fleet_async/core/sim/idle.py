"""Which of the next steps are provably empty, and skipping them.

A step is empty when running it would change nothing but the clock: no body moves or is due to
(kinematic motion, joints, attachments, physics off), no callback, plugin or per-object
callback is due, no action starts, is polled or times out, no collision check has anything new
to look at, nothing listens to every step (PRE_STEP / POST_STEP / PRE_UPDATE / POST_UPDATE
handlers, which includes a running recorder, and the GUI), no body waits to be created, and
step timing is not being logged. ``IdleSteps`` answers how many of the next steps are empty and
advances the clock over them as if they had run: every schedule stays exact because nothing in
the span was due, and collision checks that fall due in it would have found nothing new.

The drivers use it (``run_simulation`` and the mission driver); ``step_once`` never skips.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from fleet_async.core.base.events import EventBus, SimEvents
from fleet_async.core.base.scheduling import PeriodicSchedule

if TYPE_CHECKING:
    from fleet_async.core.agents.fleet import FleetMotion
    from fleet_async.core.collision.system import CollisionSystem
    from fleet_async.core.world.world import World

__all__ = ["IdleSteps"]

_PER_STEP_EVENTS = (
    SimEvents.PRE_STEP,
    SimEvents.POST_STEP,
    SimEvents.PRE_UPDATE,
    SimEvents.POST_UPDATE,
)


class IdleSteps:
    """Counts and skips empty steps for one simulation kernel.

    Args:
        timestep: Sim seconds per step.
        events: The simulation's bus.
        schedules: The simulation's callback and plugin schedules.
        world: Objects (updaters, per-object callbacks, rows, pending bodies).
        fleet: The agents' motion (engine, controllers, plugins, action queues).
        collision: The collision system.
        motion_systems: Returns the motion systems stepped each step; besides ``fleet``, only
            ``joints`` (idle when it has no moving agent) is understood, any other one makes
            every step count.
        joints: The joint motion system.
        blocked: Returns a reason every step must run (GUI, physics, timing log), or None.
    """

    def __init__(
        self,
        timestep: float,
        events: EventBus,
        schedules: Sequence[PeriodicSchedule],
        world: World,
        fleet: FleetMotion,
        collision: CollisionSystem,
        motion_systems: Callable[[], Sequence[Any]],
        joints: Any,
        blocked: Callable[[], bool],
    ) -> None:
        self._dt = timestep
        self._events = events
        self._schedules = schedules
        self._world = world
        self._fleet = fleet
        self._collision = collision
        self._motion_systems = motion_systems
        self._joints = joints
        self._blocked = blocked

    def count(self, step: int, limit: int) -> int:
        """How many of the steps ``step, step + 1, ...`` (at most ``limit``) are empty."""
        if limit <= 0 or self._blocked():
            return 0
        has = self._events.has_handlers
        if any(has(event) for event in _PER_STEP_EVENTS):
            return 0
        world = self._world
        if world.has_pending_bodies or world.updaters():
            return 0
        if len(self._joints) or any(
            m is not self._fleet and m is not self._joints for m in self._motion_systems()
        ):
            return 0
        free = self._collision.idle_steps(step, limit)
        if free:
            free = self._fleet.idle_steps(step, free)
        dt = self._dt
        for schedule in self._schedules:
            if not free:
                return 0
            free = schedule.steps_until_due(step, dt, free)
        for obj in world.objects_with_callbacks():
            if not free:
                return 0
            free = obj.callback_steps_until_due(step, dt, free)
        return free

    def skip(self, step: int, n: int) -> None:
        """Account for ``n`` empty steps from ``step`` (the caller advances the clock)."""
        self._collision.skip(step, n, self._dt)
        self._fleet.skip(step + n - 1)
