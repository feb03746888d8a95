"""Which of the next steps are provably empty, and skipping them.

A step is empty when running it would change nothing but the clock: no body moves or is due to
(kinematic motion, joints, attachments, physics off), no callback, plugin or per-object
callback is due, no action starts, is polled or times out, no collision check has anything new
to look at, nothing listens to every step (PRE_STEP / POST_STEP / PRE_UPDATE / POST_UPDATE
handlers on the simulation's bus or an object's, which includes a running recorder, and the
GUI), and step timing is not being logged. Step observers (``sim.add_step_observer``, e.g. a
trace writer) only watch, so they do not count; they hear of a skipped span from
STEPS_SKIPPED. ``IdleSteps`` answers how many of the next steps are empty and advances the
clock over them as if they had run: every schedule stays exact because nothing in the span was
due, and collision checks that fall due in it would have found nothing new.

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

__all__ = ["IdleApi", "IdleSteps"]

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
        world: Objects (updaters, per-object callbacks).
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
        pre_step, post_step, pre_update, post_update = _PER_STEP_EVENTS
        if has(pre_step) or has(post_step) or has(pre_update) or has(post_update):
            return 0
        world = self._world
        if world.has_updaters() or world.has_update_listeners() or len(self._joints):
            return 0
        fleet, joints = self._fleet, self._joints
        for system in self._motion_systems():
            if system is not fleet and system is not joints:
                return 0
        free = self._collision.idle_steps(step, limit)
        if free:
            free = self._fleet.idle_steps(step, free)
        dt = self._dt
        for schedule in self._schedules:
            if not free:
                return 0
            free = schedule.steps_until_due(step, dt, free)
        if free and world.has_object_callbacks():
            free = world.object_callback_steps(step, dt, free)
        return free

    def skip(self, step: int, n: int) -> None:
        """Account for ``n`` empty steps from ``step`` (the caller advances the clock)."""
        self._collision.skip(step, n, self._dt)
        self._fleet.skip(step + n - 1)


class IdleApi:
    """The simulation's idle-step API (mixed into the kernel), for drivers of the step loop."""

    # Provided by the simulation kernel.
    _idle: IdleSteps
    _paused: bool
    _initialized: bool
    _step_count: int
    events: EventBus

    if TYPE_CHECKING:

        @property
        def sim_time(self) -> float: ...

    def idle_steps(self, limit: int) -> int:
        """How many of the next steps (at most ``limit``) are provably empty.

        A step is empty when running it would change nothing but the clock: no body moves or
        is due to (no path or velocity command in the kinematic engine, no joint moving, no
        agent that just stopped still to have its velocity zeroed), no high-level controller
        is due (a patrol or random walk only when its pause ends; a controller without a
        ``wake_time`` every step), no agent plugin that overrides ``on_step`` (batteries do
        not: a standing robot's charge follows a formula) and no ``update(dt)`` override
        runs, no callback, plugin or per-object
        callback is due, no action is due to start, be polled or time out, no collision check
        has anything new to examine (nothing moved and no object joined or left since the last
        check), nothing is subscribed to PRE_STEP / POST_STEP / PRE_UPDATE / POST_UPDATE on
        the simulation's bus or PRE_UPDATE / POST_UPDATE on an object's (a running recorder is
        such a subscriber), and neither the GUI, ``physics=True``,
        step-timing logs nor a motion system other than the built-in ones needs every step.
        Action and collision events, the monitor (fed once per frame by ``run_simulation``)
        and the mission runtime's own timers do not count: the mission driver combines this
        answer with its next timer itself.

        The answer only depends on the simulation's state, so it stays true until something
        changes it (a command, a pose write, a registration); skip the steps at once.

        Args:
            limit: The most steps to look ahead (>= 0).

        Returns:
            ``k`` in ``[0, limit]``: the steps ``step_count .. step_count + k - 1`` are empty;
            ``sim.skip_steps(k)`` then gives exactly the state ``k`` calls of ``step_once()``
            would. 0 while paused or before the first step.
        """
        if self._paused or not self._initialized:
            return 0
        return self._idle.count(self._step_count, int(limit))

    def skip_steps(self, n: int) -> None:
        """Advance the clock over ``n`` empty steps as if ``step_once()`` had run ``n`` times.

        ``step_count`` grows by ``n`` and ``sim_time`` stays ``step_count * timestep``;
        callbacks, plugins, per-object callbacks, action timers and collision checks keep
        their exact schedules (none of them was due in the span, or a collision check that
        was due would have found nothing new). Emits ``STEPS_SKIPPED`` (``sim``, ``step``: the
        first skipped step, ``count``: ``n``, ``sim_time``: after the span) for recorders of
        the span; no per-step event is emitted.

        Raises:
            ValueError: if ``n`` is negative or more than ``idle_steps(n)`` (one of the steps
                is not provably empty).
        """
        if n < 0 or self.idle_steps(n) < n:
            raise ValueError(
                f"skip_steps: {n} steps are not provably empty from step {self._step_count} "
                f"(idle_steps says {max(self.idle_steps(max(n, 0)), 0)}); run step_once()"
            )
        self._skip(n)

    def skip_idle_steps(self, limit: int) -> int:
        """Skip as many of the next ``limit`` steps as are provably empty, in one look
        (``idle_steps`` then ``skip_steps``, without checking twice); return how many."""
        n = self.idle_steps(limit)
        self._skip(n)
        return n

    def _skip(self, n: int) -> None:
        if n == 0:
            return
        first = self._step_count
        self._idle.skip(first, n)
        self._step_count += n
        if self.events.has_handlers(SimEvents.STEPS_SKIPPED):
            self.events.emit(
                SimEvents.STEPS_SKIPPED, sim=self, step=first, count=n, sim_time=self.sim_time
            )
