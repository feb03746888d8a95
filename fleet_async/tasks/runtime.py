"""The mission runtime: drives the step loop from inside anyio, parks and wakes missions.

The step loop stays the only clock. Between two steps every mission runs until it parks on a
sim-time awaitable; only then does the driver step. The driver knows missions have settled
through a runnable counter: +1 when a mission is spawned, -1 when it parks, +1 by whoever
wakes it (at wake time, not when it resumes), -1 when it exits. At 0 the driver takes two more
checkpoints (asyncio runs some callbacks one loop iteration late) and looks again.

After a step, wakes are delivered in a canonical order: by the mission's key (its spawn path:
main is (0,), its n-th child (0, n), ...), never by ``id()`` or arrival. On trio, whose run
queue is shuffled on purpose, woken missions run one at a time in that order; on asyncio the
FIFO ready queue keeps the order, so they run as one batch. Then sim-time timeouts fire (an
action that completes in the same step as its timeout counts as completed), then missions
settle again.
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

import anyio
import anyio.lowlevel

from fleet_async.core.events import SimEvents
from fleet_async.core.types import ActionStatus
from fleet_async.tasks.errors import (
    ActionCancelledError,
    ActionFailedError,
    MissionDeadlockError,
    MissionStalledError,
    NoMissionRuntimeError,
)
from fleet_async.tasks.parking import Waiter, parker_for_backend

if TYPE_CHECKING:
    from fleet_async.core.action import Action
    from fleet_async.core.simulation import MultiRobotSimulationCore
    from fleet_async.tasks.timeouts import SimTimeout

__all__ = ["Mission", "Runtime"]

_EPS = 1e-9
# Waits that stepping the simulation can end; a mission parked on anything else (sim Events,
# locks, joins) can only be woken by another mission.
_PROGRESSING = frozenset({"timer", "action", "condition", "event"})


def _action_error(action: Action) -> BaseException | None:
    """What awaiting ``action`` raises once it has ended (None when it completed)."""
    if action.status is ActionStatus.FAILED:
        return ActionFailedError(action)
    if action.status is ActionStatus.CANCELLED:
        return ActionCancelledError(action)
    return None


class Mission:
    """Bookkeeping for one mission task."""

    __slots__ = ("children", "key", "name", "waiter")

    def __init__(self, key: tuple[int, ...], name: str) -> None:
        self.key = key
        self.name = name
        self.children = 0
        self.waiter: Waiter | None = None

    def child_key(self) -> tuple[int, ...]:
        """Key of the next mission this one spawns."""
        self.children += 1
        return (*self.key, self.children)


class Runtime:
    """Runs missions against one simulation on one anyio backend.

    Args:
        sim: The simulation (the runtime installs itself as ``sim``'s mission runtime).
        backend: "asyncio" or "trio".
        watchdog: Wall seconds a mission may hold the clock before MissionStalledError.
    """

    def __init__(self, sim: MultiRobotSimulationCore, backend: str, watchdog: float = 30.0) -> None:
        self.sim = sim
        self.parker = parker_for_backend(backend, self)
        self.park = self.parker.park
        """``await runtime.park(waiter)``: suspend the current mission until ``wake(waiter)``
        (counted as parked; cancellable by anyio scopes)."""
        self.watchdog = watchdog
        self.runnable = 0
        self.alive = 0
        self._missions: dict[Any, Mission] = {}  # backend task object -> mission
        self._seq = itertools.count()
        self._timers: dict[int, list[Waiter]] = {}  # wake step -> waiters (unordered)
        # Pending wakes, delivered in (mission key, sequence) order; sorted lazily, descending,
        # so the next one is popped from the end.
        self._wakes: list[tuple[tuple[int, ...], int, Waiter, Any, BaseException | None]] = []
        self._wakes_sorted = True
        self._actions: dict[int, Waiter] = {}
        self._conditions: dict[int, tuple[Waiter, Callable[[], bool]]] = {}
        self._event_waits: dict[str, dict[int, tuple[Waiter, Callable[..., bool] | None]]] = {}
        self._timeouts: list[tuple[int, int, SimTimeout]] = []
        self._driver: Waiter | None = None
        self._driver_since = 0.0  # wall time the driver started waiting for missions
        self._event_handlers: dict[str, Callable[..., None]] = {}
        # Abort hooks bound once: a bound method per wait is garbage the collector chases.
        self._on_timer_abort = self._undo_timer
        self._on_action_abort = self._undo_action
        sim.events.on(SimEvents.ACTION_COMPLETED, self._on_action_end, priority=1_000_000)
        sim.events.on(SimEvents.ACTION_FAILED, self._on_action_end, priority=1_000_000)

    def close(self) -> None:
        """Detach from the simulation."""
        self.sim.events.off(SimEvents.ACTION_COMPLETED, self._on_action_end)
        self.sim.events.off(SimEvents.ACTION_FAILED, self._on_action_end)
        for name, handler in self._event_handlers.items():
            self.sim.events.off(name, handler)
        self._event_handlers.clear()

    # ----- missions -----------------------------------------------------------------------

    def current(self, what: str) -> Mission:
        """The mission running now.

        Raises:
            NoMissionRuntimeError: outside a mission started by fleet_async.
        """
        try:
            task = self.parker.current_task()
        except RuntimeError:  # no running event loop
            task = None
        mission = self._missions.get(task)
        if mission is None:
            raise NoMissionRuntimeError(
                f"{what} must be awaited inside a mission started by fleet_async "
                "(fleet_async.run(sim, main), sim.task_group(), sim.gather() or sim.race())"
            )
        return mission

    def spawn(
        self,
        tg: Any,
        fn: Callable[..., Awaitable[Any]],
        args: tuple[Any, ...],
        key: tuple[int, ...],
        name: str,
        on_done: Callable[[], None] | None = None,
        box: list[Any] | None = None,
    ) -> None:
        """Start a mission in anyio task group ``tg``; it counts as runnable from now.

        A new mission first parks on a start gate, and the gates open in key order like any
        other wake: the backend's scheduling order of new tasks never decides which mission
        runs first.
        """
        mission = Mission(key, name)
        gate = Waiter(mission, "start")
        self.runnable += 1
        self.alive += 1
        self.schedule_wake(gate)
        tg.start_soon(self._run_mission, fn, args, mission, gate, on_done, box, name=name)

    async def _run_mission(
        self,
        fn: Callable[..., Awaitable[Any]],
        args: tuple[Any, ...],
        mission: Mission,
        gate: Waiter,
        on_done: Callable[[], None] | None,
        box: list[Any] | None,
    ) -> None:
        task = self.parker.current_task()
        self._missions[task] = mission
        try:
            await self.park(gate)
            result = await fn(*args)
            if box is not None:
                box.append(result)
        except anyio.get_cancelled_exc_class():
            raise
        except BaseException as exc:
            notes = getattr(exc, "__notes__", [])
            if hasattr(exc, "add_note") and not any(n.startswith("in mission ") for n in notes):
                exc.add_note(f"in mission {mission.name!r} at sim time {self.sim.sim_time:.3f} s")
            if self.sim.events.has_handlers(SimEvents.MISSION_FAILED):  # e.g. sim.kpis()
                self.sim.events.emit(
                    SimEvents.MISSION_FAILED, sim=self.sim, mission=mission.name, error=exc
                )
            raise
        finally:
            del self._missions[task]
            self.alive -= 1
            if on_done is not None:
                on_done()
            self.decrement()

    # ----- counting and parking -------------------------------------------------------------

    def decrement(self) -> None:
        """The current mission parks or exits."""
        self.runnable -= 1
        if self.runnable != 0:
            return
        if self.parker.one_at_a_time and self._wakes and self._driver is not None:
            # Baton: while the driver waits, the mission that just parked hands the turn
            # straight to the next wake in key order, without a round trip to the driver.
            _, _, waiter, value, error = self._next_wake()
            self.wake(waiter, value, error)
            return
        if self._driver is not None and not self._driver.done:
            driver, self._driver = self._driver, None
            driver.done = True
            self.parker.wake(driver)

    def note_parked(self) -> None:
        """The current mission waits on something that is not a sim park (a task-group join)."""
        self.decrement()

    def count_wake(self) -> None:
        """A parked mission is about to run again (called by whoever wakes it)."""
        self.runnable += 1

    def aborted(self, waiter: Waiter) -> None:
        """A parked mission was cancelled: count it runnable and undo what its wait set up."""
        if waiter.done:
            return
        waiter.done = True
        self.runnable += 1  # the cancelled task runs again
        if waiter.on_abort is not None:
            waiter.on_abort(waiter)

    def _undo_timer(self, waiter: Waiter) -> None:
        bucket = waiter.target
        if waiter in bucket:
            bucket.remove(waiter)

    def _undo_action(self, waiter: Waiter) -> None:
        action = waiter.target
        self._actions.pop(id(action), None)
        if not action.is_complete():
            action.cancel()

    def wake(self, waiter: Waiter, value: Any = None, error: BaseException | None = None) -> None:
        """Resume ``waiter`` now (counted at once)."""
        if waiter.done:
            return
        waiter.done = True
        self.runnable += 1
        self.parker.wake(waiter, value, error)

    def schedule_wake(
        self, waiter: Waiter, value: Any = None, error: BaseException | None = None
    ) -> None:
        """Resume ``waiter`` at the next wake delivery, in key order."""
        self._wakes.append((waiter.mission.key, next(self._seq), waiter, value, error))
        self._wakes_sorted = False

    def _next_wake(self) -> tuple[tuple[int, ...], int, Waiter, Any, BaseException | None]:
        wakes = self._wakes
        if not self._wakes_sorted:
            wakes.sort(reverse=True)  # sequence numbers are unique: waiters never compared
            self._wakes_sorted = True
        return wakes.pop()

    # ----- settling and stepping --------------------------------------------------------------

    async def settle(self) -> None:
        """Deliver pending wakes in key order until every mission is parked (or done).

        Raises:
            MissionStalledError: (from :meth:`watch`) missions kept the driver waiting for
                longer than the watchdog allows.
        """
        while True:
            await self._quiesce()
            if not self._wakes:
                return
            if self.parker.one_at_a_time:
                _, _, waiter, value, error = self._next_wake()
                self.wake(waiter, value, error)
            else:
                wakes, self._wakes = self._wakes, []
                wakes.sort()  # sequence numbers are unique: waiters never compared
                self._wakes_sorted = True
                for _, _, waiter, value, error in wakes:
                    self.wake(waiter, value, error)

    async def watch(self) -> None:
        """The watchdog, a task beside the missions (not one of them): if the driver has
        waited for missions for more than ``watchdog`` wall seconds, it fails the driver's
        wait with MissionStalledError. One task for the whole run, rather than a cancel
        scope around every settle, keeps the per-step cost down."""
        while True:
            await anyio.sleep(self.watchdog / 4)
            driver = self._driver
            if driver is None or driver.done:
                continue
            if time.perf_counter() - self._driver_since <= self.watchdog:
                continue
            running = sorted(m.name for m in self._missions.values() if m.waiter is None)
            self._driver = None
            driver.done = True
            self.parker.wake(
                driver,
                error=MissionStalledError(
                    f"missions {running} held the clock for more than {self.watchdog} s of "
                    f"wall time at sim time {self.sim.sim_time:.3f} s "
                    "(a wall-clock sleep or I/O inside a mission?)"
                ),
            )

    async def _quiesce(self) -> None:
        """Wait until the runnable count is zero."""
        while True:
            if self.runnable == 0:
                if not self.parker.needs_recheck:
                    return
                # asyncio resumes a cancelled task (which then counts itself runnable) one
                # loop iteration after the cancel: look again after it had its turn.
                await anyio.lowlevel.cancel_shielded_checkpoint()
                await anyio.lowlevel.cancel_shielded_checkpoint()
                if self.runnable == 0:
                    return
                continue
            driver = Waiter(None, "driver")
            self._driver = driver
            self._driver_since = time.perf_counter()
            await self.parker.wait_driver(driver)

    def check_deadlock(self) -> None:
        """Raise if missions are alive but nothing that stepping does can wake any of them."""
        if self.alive == 0 or self._timers or self._timeouts or self._wakes:
            return
        parked = [m.waiter for m in self._missions.values() if m.waiter is not None]
        if any(w.kind in _PROGRESSING for w in parked):
            return
        waits = sorted((w.mission.name, w.kind) for w in parked)
        raise MissionDeadlockError(
            f"deadlock at sim time {self.sim.sim_time:.3f} s: missions are alive but every one "
            f"waits on another mission: {waits}"
        )

    async def after_step(self) -> None:
        """Deliver this step's wakes in key order, settle, then fire due sim-time timeouts."""
        step = self.sim.step_count
        for waiter in self._timers.pop(step, ()):
            self.schedule_wake(waiter)
        if self._conditions:
            ready = sorted(self._conditions.items(), key=lambda kv: kv[1][0].mission.key)
            for ident, (waiter, predicate) in ready:
                if predicate():
                    del self._conditions[ident]
                    self.schedule_wake(waiter)
        await self.settle()
        due = []
        while self._timeouts and self._timeouts[0][0] <= step:
            due.append(heapq.heappop(self._timeouts)[2])
        for timeout in due:
            timeout.fire()
        if due:
            await self.settle()

    # ----- sim-time waits ---------------------------------------------------------------------

    def steps_for(self, seconds: float) -> int:
        """Whole steps until ``seconds`` of sim time have passed (0 for <= 0)."""
        if not math.isfinite(seconds):
            raise ValueError(f"sim time must be finite, got {seconds!r}")
        return max(0, math.ceil(seconds / self.sim.params.timestep - _EPS))

    # These return the park itself rather than being coroutines, so an ``await sim.sleep()``
    # or ``await agent.move()`` resumes through one frame fewer on every wake.

    def sleep_steps(self, steps: int, what: str = "sim.sleep") -> Awaitable[None]:
        """Park the current mission for ``steps`` steps (await the result at once)."""
        mission = self.current(what)
        if steps <= 0:
            return anyio.lowlevel.checkpoint()
        waiter = Waiter(mission, "timer")
        bucket = self._timers.setdefault(self.sim.step_count + steps, [])
        waiter.target, waiter.on_abort = bucket, self._on_timer_abort
        bucket.append(waiter)
        return self.park(waiter)

    def wait_action(self, action: Action, what: str) -> Awaitable[Action]:
        """Park until a queued ``action`` ends (await the result at once); it returns the
        action, or raises ActionFailedError / ActionCancelledError.

        If the waiting mission is cancelled, the action is cancelled too: a queued action is
        dropped, a running one stops its robot in this step.
        """
        mission = self.current(what)
        if action.is_complete():
            return self._ended(action)
        key = id(action)
        if key in self._actions:
            raise RuntimeError(f"{what}: another mission is already waiting on this action")
        waiter = Waiter(mission, "action")
        waiter.target, waiter.on_abort = action, self._on_action_abort
        self._actions[key] = waiter
        return self.park(waiter)

    async def _ended(self, action: Action) -> Action:
        await anyio.lowlevel.checkpoint()
        error = _action_error(action)
        if error is not None:
            raise error
        return action

    def _on_action_end(self, agent: Any = None, action: Any = None, **_: Any) -> None:
        waiter = self._actions.pop(id(action), None)
        if waiter is not None:
            self.schedule_wake(waiter, action, _action_error(action))

    async def wait_until(self, predicate: Callable[[], bool], what: str = "sim.wait_until") -> None:
        """Park until ``predicate()`` is true after a step (returns at once if true now)."""
        mission = self.current(what)
        if predicate():
            await anyio.lowlevel.checkpoint()
            return
        waiter = Waiter(mission, "condition")
        key = id(waiter)

        def undo(_: Waiter) -> None:
            self._conditions.pop(key, None)

        waiter.on_abort = undo
        self._conditions[key] = (waiter, predicate)
        await self.park(waiter)

    async def wait_event(self, name: str, where: Callable[..., bool] | None) -> dict[str, Any]:
        """Park until event ``name`` is emitted with a payload ``where`` accepts; return it."""
        mission = self.current("sim.events.wait")
        waiter = Waiter(mission, "event")
        key = id(waiter)
        table = self._event_waits.setdefault(name, {})
        if name not in self._event_handlers:
            handler = self._event_handler(name)
            self._event_handlers[name] = handler
            self.sim.events.on(name, handler, priority=1_000_000)

        def undo(_: Waiter) -> None:
            table.pop(key, None)

        waiter.on_abort = undo
        table[key] = (waiter, where)
        result: dict[str, Any] = await self.park(waiter)
        return result

    def _event_handler(self, name: str) -> Callable[..., None]:
        def handler(**payload: Any) -> None:
            table = self._event_waits.get(name)
            if not table:
                return
            for key, (waiter, where) in list(table.items()):
                if where is None or where(**payload):
                    del table[key]
                    self.schedule_wake(waiter, dict(payload))

        return handler

    # ----- factories behind the sim's mission API (core never imports this package) ------------

    def timeout(
        self, seconds: float, fail: bool, shield: bool = False, absolute: bool = False
    ) -> SimTimeout:
        """A sim-time cancel scope ``seconds`` from now (or at sim time ``seconds``)."""
        from fleet_async.tasks.timeouts import SimTimeout  # cycle

        if absolute:
            step = max(0, math.ceil(seconds / self.sim.params.timestep - _EPS))
        else:
            step = self.sim.step_count + self.steps_for(seconds)
        return SimTimeout(self, step, fail, shield)

    def task_group(self) -> Any:
        """A new sim-aware task group."""
        from fleet_async.tasks.groups import SimTaskGroup  # cycle

        return SimTaskGroup(self)

    async def gather(self, *items: Any) -> list[Any]:
        """Run missions concurrently; results in argument order."""
        from fleet_async.tasks.groups import gather  # cycle

        return await gather(self, *items)

    async def race(self, *items: Any) -> tuple[int, Any]:
        """First mission to finish wins; the rest are cancelled."""
        from fleet_async.tasks.groups import race  # cycle

        return await race(self, *items)

    def event_stream(self, name: str, where: Callable[..., bool] | None) -> Any:
        """An async iterator over ``name`` events (``sim.events.stream``)."""
        from fleet_async.tasks.sync import EventStream  # cycle

        return EventStream(self.sim, name, where)

    def mission_rng(self) -> Any:
        """A random generator for the current mission, derived from the seed and its key."""
        import numpy as np

        mission = self.current("sim.mission_rng")
        return np.random.default_rng([self.sim.params.seed, 0x3A55, *mission.key])

    def add_timeout(self, timeout: SimTimeout, deadline_step: int) -> tuple[int, int, SimTimeout]:
        """Register a sim-time cancel scope to fire at ``deadline_step``."""
        entry = (deadline_step, next(self._seq), timeout)
        heapq.heappush(self._timeouts, entry)
        return entry

    def remove_timeout(self, entry: tuple[int, int, SimTimeout]) -> None:
        """Forget a timeout whose scope was left before it fired."""
        if entry in self._timeouts:
            self._timeouts.remove(entry)
            heapq.heapify(self._timeouts)
