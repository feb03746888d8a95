"""The mission runtime of a simulation: what the simulation's mission API delegates to.

It owns the kernel (the event queue and the missions), the root group, and the waits that only
the step loop can end (actions, predicates, bus events), and it brackets each step so that what
a step causes is ordered at the step's end: actions that ended, in agent order, then predicates
that became true, in the order they were registered.

It is made on the first mission call on a simulation (so timers, events, requests and missions
can be made before a run, and start when it starts) and lives across runs: a run that stops at
``until`` leaves its missions waiting here, and the next ``fleet_async.run`` continues them.
A run that fails, is stopped from outside or ends with ``then="cancel"``, and
``sim.end_missions()``, end it; the next mission call makes a fresh one.
"""

from __future__ import annotations

import logging
import math
import sys
from collections.abc import Awaitable, Callable, Generator, Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from fleet_async.core.missions import SimEvents, register_mission_hook, steps_for
from fleet_async.tasks.conditions import AllOf, AnyOf
from fleet_async.tasks.groups import Nursery, TaskGroup, gather, race
from fleet_async.tasks.kernel import STEP, Kernel, SimEvent, Timeout
from fleet_async.tasks.missions import Mission, dispatch
from fleet_async.tasks.scopes import CancelScope
from fleet_async.tasks.sync import Event, EventStream
from fleet_async.tasks.waits import ActionWait, BusWait, PredicateWait

if sys.version_info < (3, 11):  # pragma: no cover  # anyio brings the backport
    from exceptiongroup import BaseExceptionGroup

if TYPE_CHECKING:
    from fleet_async.core.missions import MissionSim

__all__ = ["Runtime"]

logger = logging.getLogger(__name__)


class Runtime:
    """Serves one simulation's sim-time awaits, across runs (see the module doc).

    Args:
        sim: The simulation; its step count is the kernel's clock.
    """

    @classmethod
    def of(cls, sim: MissionSim) -> Runtime:
        """The runtime of ``sim``, made and installed if it has none."""
        runtime = sim.mission_runtime
        if runtime is None:
            runtime = cls(sim)
            sim.set_mission_runtime(runtime)
        assert isinstance(runtime, Runtime)
        return runtime

    def __init__(self, sim: MissionSim) -> None:
        self.sim = sim
        self.driving = False
        """Whether a ``fleet_async.run`` is driving the missions now."""
        self.closed = False
        self.kernel = Kernel(sim.step_count, sim.params.timestep)
        self.root = Nursery(self.kernel, CancelScope(self.kernel, root=True), owner=None)
        """The run's root group: the main mission and what ``sim.spawn`` starts."""
        self.action_waits: dict[int, ActionWait] = {}
        self.predicates: dict[int, PredicateWait] = {}
        self.bus_waits: dict[str, dict[int, BusWait]] = {}
        self.streams: list[EventStream] = []
        self._outcomes: list[tuple[int, ActionWait]] = []
        self._bus_handlers: dict[str, Callable[..., None]] = {}
        self.kernel.on_failure = self._on_mission_failed
        self.kernel.on_unhandled = self._on_unhandled
        sim.events.on(SimEvents.ACTION_COMPLETED, self._on_action_end, priority=1_000_000)
        sim.events.on(SimEvents.ACTION_FAILED, self._on_action_end, priority=1_000_000)

    def touch(self) -> None:
        """Bring the clock to the simulation's step (outside runs the simulation may have
        been stepped by hand; inside one, the driver keeps it)."""
        if not self.driving:
            self.kernel.now = self.sim.step_count

    def mission_names(self) -> list[str]:
        """Names of the missions alive, in start order."""
        return [mission.name for mission in sorted(self.kernel.missions, key=_by_key)]

    def end(self) -> None:
        """``sim.end_missions()``: cancel what is alive at the current step, serve their
        cleanup at this step (without stepping), close what still waits, and detach.

        Raises:
            RuntimeError: during a run.
            BaseException: a failure of a mission's cleanup (several as an ExceptionGroup).
        """
        if self.driving:
            raise RuntimeError(
                "sim.end_missions() was called during a run: cancel missions from inside it "
                "(mission.cancel(), a task group's cancel_scope) or stop the run with until="
            )
        self.touch()
        try:
            self.cancel_all("sim.end_missions() was called")
        finally:
            self.close()
        errors = self.root.errors
        if errors:
            from fleet_async.tasks.groups import lone_error  # groups build on missions

            raise lone_error(BaseExceptionGroup("missions failed while ending", errors))

    def cancel_all(self, why: str) -> None:
        """Cancel every mission at the current step, leaving the events due now unprocessed:
        serve their cleanup at this step, then close those still waiting (their ``finally``
        blocks run without sim awaits)."""
        kernel = self.kernel
        kernel.drop_due()
        self.root.cancel_scope.cancel()
        _drive_here(dispatch(kernel))
        self.close_missions(why)

    def close_missions(self, why: str) -> None:
        """End the missions still alive without resuming them (their ``finally`` blocks run),
        the last started first, so that children end before the groups that wait for them."""
        missions = sorted(self.kernel.missions, key=_by_key)
        if missions:
            logger.warning("closing missions %s: %s", [m.name for m in missions], why)
        for mission in reversed(missions):
            mission.close()

    def close(self) -> None:
        """Detach from the simulation (its next mission call makes a fresh runtime)."""
        if self.closed:
            return
        self.closed = True
        if self.sim.mission_runtime is self:
            self.sim.set_mission_runtime(None)
        events = self.sim.events
        events.off(SimEvents.ACTION_COMPLETED, self._on_action_end)
        events.off(SimEvents.ACTION_FAILED, self._on_action_end)
        for name, handler in self._bus_handlers.items():
            events.off(name, handler)
        self._bus_handlers.clear()
        for stream in self.streams:
            stream.close()

    # ----- the step bracket (called by the driver) ---------------------------------------------

    def step(self) -> None:
        """Run one simulation step; order what it caused at its end."""
        kernel = self.kernel
        kernel.in_step = 1
        try:
            self.sim.step_once()
        finally:
            kernel.in_step = 0
        kernel.now = self.sim.step_count
        if self._outcomes:
            outcomes, self._outcomes = self._outcomes, []
            outcomes.sort(key=_agent)  # stable: ends of one agent's actions in their order
            kernel.schedule_run([wait for _, wait in outcomes], STEP)
        if self.predicates:
            for key, pending in list(self.predicates.items()):
                if pending.callbacks and pending.predicate():
                    del self.predicates[key]
                    pending.succeed()

    def step_driven(self, besides_predicates: bool = False) -> bool:
        """Whether stepping can end something a mission waits on (an action, a predicate
        unless ``besides_predicates``, a bus event, a stream item)."""
        return bool(
            self.action_waits
            or (not besides_predicates and any(w.callbacks for w in self.predicates.values()))
            or any(stream.waiting for stream in self.streams)
            or any(wait.callbacks for table in self.bus_waits.values() for wait in table.values())
        )

    def watches_predicates(self) -> bool:
        """Whether a mission waits on a ``sim.wait_until`` predicate (checked every step)."""
        return bool(self.predicates) and any(wait.callbacks for wait in self.predicates.values())

    def outcome(self, wait: ActionWait) -> None:
        """An awaited action ended during the step: order it among the step's outcomes."""
        self._outcomes.append((wait.agent.object_id, wait))

    def _on_action_end(self, agent: Any = None, action: Any = None, **_: Any) -> None:
        wait = self.action_waits.pop(id(action), None)
        if wait is not None:
            wait.settle(in_step=bool(self.kernel.in_step))

    def _on_unhandled(self, event: SimEvent) -> None:
        """A failed event nobody waited on: it fails the run now (SimPy's rule)."""
        error: BaseException = event.raw_value
        where = getattr(event, "created_at", None)
        made = f" (made at {where})" if where else ""
        note = (
            f"{event!r}{made} failed at sim time {self.kernel.now * self.kernel.timestep:.3f} s "
            "and nobody waited on it: await it, or set 'event.defused = True' to let it fail "
            "unobserved"
        )
        if sys.version_info >= (3, 11):
            error.add_note(note)
        else:  # pragma: no cover  # no notes before 3.11: say it in the log
            logger.error(note)
        self.root.fail(error)

    def _on_mission_failed(self, mission: Mission, error: BaseException) -> None:
        events = self.sim.events
        if events.has_handlers(SimEvents.MISSION_FAILED):  # e.g. KPIs, a trace
            events.emit(SimEvents.MISSION_FAILED, sim=self.sim, mission=mission.name, error=error)

    def add_bus_wait(self, wait: BusWait) -> None:
        """Register ``sim.events.wait`` (one bus handler per event name)."""
        table = self.bus_waits.setdefault(wait.name, {})
        table[id(wait)] = wait
        if wait.name not in self._bus_handlers:
            handler = self._bus_handler(table)
            self._bus_handlers[wait.name] = handler
            self.sim.events.on(wait.name, handler, priority=1_000_000)

    def _bus_handler(self, table: dict[int, BusWait]) -> Callable[..., None]:
        def handler(**payload: Any) -> None:
            for key, wait in list(table.items()):
                if wait.where is None or wait.where(**payload):
                    del table[key]
                    wait.succeed(dict(payload))

        return handler

    # ----- the mission API's implementation ----------------------------------------------------

    def steps_for(self, seconds: float, what: str = "sim.sleep") -> int:
        """Whole steps that cover ``seconds`` of sim time (rounded up).

        Raises:
            ValueError: if ``seconds`` is negative or not finite.
        """
        if not math.isfinite(seconds) or seconds < 0:
            raise ValueError(f"{what}: expected a finite number of seconds >= 0, got {seconds!r}")
        return max(0, steps_for(seconds, self.kernel.timestep))

    def timeout(self, seconds: float, value: Any = None, what: str = "sim.timeout") -> Timeout:
        """An event that succeeds with ``value`` after ``seconds`` of sim time."""
        return Timeout(self.kernel, self.steps_for(seconds, what), value)

    def sleep_until(self, t: float) -> Timeout:
        """An event that succeeds at sim time ``t`` (at once if it has passed)."""
        if not math.isfinite(t):
            raise ValueError(f"sim.sleep_until: expected a finite sim time, got {t!r}")
        step = steps_for(t, self.kernel.timestep)
        return Timeout(self.kernel, max(0, step - self.kernel.now))

    def scope(
        self, seconds: float | None, fail: bool, shield: bool = False, absolute: bool = False
    ) -> CancelScope:
        """A sim-time cancel scope that fires ``seconds`` from now (or at sim time ``seconds``
        if ``absolute``; never if None)."""
        if seconds is None:
            return CancelScope(self.kernel, None, shield, fail)
        if absolute:
            if not math.isfinite(seconds):
                raise ValueError(f"deadline: expected a finite sim time, got {seconds!r}")
            step = max(0, steps_for(seconds, self.kernel.timestep))
        else:
            step = self.kernel.now + self.steps_for(seconds, "sim.move_on_after")
        return CancelScope(self.kernel, step, shield, fail)

    def wait_action(
        self, agent: Any, action: Any, detached: bool = False, what: str = "agent.submit"
    ) -> ActionWait:
        """The event for a queued action (see :class:`~fleet_async.tasks.waits.ActionWait`);
        asking twice for the same pending action gives the same event, which every waiter
        shares."""
        existing = self.action_waits.get(id(action))
        if existing is not None and existing.action is action:
            return existing
        return ActionWait(self, agent, action, detached, what)

    def wait_until(self, predicate: Callable[[], bool]) -> PredicateWait:
        """An event that succeeds once ``predicate()`` holds (now, or after a step)."""
        return PredicateWait(self, predicate)

    def wait_event(self, name: str, where: Callable[..., bool] | None) -> BusWait:
        """An event that succeeds with the payload of the next matching bus event."""
        return BusWait(self, name, where)

    def event_stream(self, name: str, where: Callable[..., bool] | None) -> EventStream:
        """An async iterator over matching bus events (closed when the run ends)."""
        stream = EventStream(self, name, where)
        self.streams.append(stream)
        return stream

    def task_group(self) -> TaskGroup:
        """A new task group of missions."""
        return TaskGroup(self.kernel)

    def gather(self, *items: Any) -> Awaitable[list[Any]]:
        """Run missions concurrently; results in argument order."""
        return gather(self.kernel, *items)

    def race(self, *items: Any) -> Awaitable[tuple[int, Any]]:
        """First mission to finish wins; the rest are cancelled."""
        return race(self.kernel, *items)

    def spawn(
        self, fn: Callable[..., Awaitable[Any]] | Awaitable[Any], *args: Any, name: str | None
    ) -> Mission:
        """Start a mission in the run's root group (it runs until it ends, or the run stops)."""
        return self.root.start(fn, args, name)

    def any_of(self, events: Iterable[SimEvent]) -> AnyOf:
        """An event that triggers when the first of ``events`` is processed."""
        return AnyOf(self.kernel, events)

    def all_of(self, events: Iterable[SimEvent]) -> AllOf:
        """An event that triggers when every one of ``events`` is processed."""
        return AllOf(self.kernel, events)

    def event(self) -> Event:
        """A new one-shot Event."""
        return Event(self.sim)

    def current_mission(self, what: str) -> Mission:
        """The mission running now."""
        return self.kernel.require_current(what)

    def mission_rng(self) -> np.random.Generator:
        """A generator for the current mission, derived from the seed and its key."""
        mission = self.kernel.require_current("sim.mission_rng")
        # The simulation's seed sequence for this key: after sim.reseed it follows the new seed.
        return np.random.default_rng(self.sim.seed_sequence(0x3A55, *mission.key))


def _agent(entry: tuple[int, ActionWait]) -> int:
    return entry[0]


def _by_key(mission: Mission) -> tuple[int, ...]:
    return mission.key


def _drive_here(coro: Generator[Any, Any, None]) -> None:
    """Drive ``dispatch`` without a host loop: a non-sim await in cleanup cannot be served
    here, so the mission gets an error at it."""
    try:
        coro.send(None)
        while True:
            coro.throw(
                RuntimeError(
                    "a mission's cleanup awaited something that is not a sim-time await "
                    "while its missions were being ended outside a run"
                )
            )
    except StopIteration:
        pass


register_mission_hook("mission_runtime", Runtime.of)
