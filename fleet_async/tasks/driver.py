"""The run's driver: steps the simulation between event batches, paces, watches for stalls.

Each turn processes the events due at the current step (``dispatch``), decides whether the
run is over (``until`` reached, the ``until`` event processed, no mission left, a deadlock),
and otherwise advances the clock: one step, or a jump over provably empty steps up to the
next due event.
"""

from __future__ import annotations

import asyncio
import math
import time
import warnings
from typing import TYPE_CHECKING, Any

import anyio
import anyio.lowlevel

from fleet_async.tasks.clock_watch import ClockWatch
from fleet_async.tasks.errors import (
    MissionDeadlockError,
    MissionStalledError,
    NoMissionRuntimeError,
)
from fleet_async.tasks.missions import dispatch

if TYPE_CHECKING:
    from fleet_async.tasks.kernel import SimEvent
    from fleet_async.tasks.missions import Mission
    from fleet_async.tasks.runtime import Runtime

__all__ = ["Driver"]

# Pacing's view of the wall: module attributes so tests can run pacing on a fake clock.
_wall_clock = time.perf_counter
_wall_sleep = anyio.sleep

_YIELD_EVERY = 0.05
"""Wall seconds between the driver's checkpoints on the host loop when it is not paced, so
other tasks of the host loop (a live viewer, a server) keep running."""
_JUMP_LIMIT_S = 3600.0
"""Sim seconds the driver jumps at most in one go when no mission event is due (missions
waiting on actions only): idle_steps knows the actions' timers, and a run in which nothing at
all can happen still moves in bounded jumps."""
_WARN_AFTER = 1.0
"""Wall seconds a mission may hold the clock before one warning says so."""
PREDICATE_PATIENCE_S = 3600.0
"""Sim seconds missions may wait on ``sim.wait_until`` predicates alone (no timer due, no
action or bus event pending) while nothing in the simulation changes, before the run calls it
a deadlock: a predicate over a world where nothing moves can only change with the clock, and
waiting for a time is ``sim.sleep_until``'s job."""


class Driver:
    """Runs the missions of one ``fleet_async.run`` (see ``fleet_async.tasks.run``)."""

    def __init__(
        self,
        runtime: Runtime,
        until_step: int | None,
        until_event: SimEvent | None,
        then: str,
        on_deadlock: str,
        watchdog: float,
    ) -> None:
        self.runtime = runtime
        self.until_step = until_step
        self.until_event = until_event
        self.then = then
        self.on_deadlock = on_deadlock
        self.watchdog = watchdog
        # Shielded, so that inside it the effective deadline tells whether a mission cancelled
        # an anyio scope it entered (see _anyio_scope_misuse); a stop from outside reaches
        # the driver through the watchdog task, which cancels this scope.
        self.scope = anyio.CancelScope(shield=True)
        self.stalled: MissionStalledError | None = None
        self._cancel_exc = anyio.get_cancelled_exc_class()
        self._idle_predicate_steps = 0

    def ends_runtime(self) -> bool:
        """Whether the runtime ends with this run (nothing left waiting, or "cancel")."""
        return self.then == "cancel" or not self.runtime.kernel.missions

    async def run(self) -> None:
        """Drive until the run is over, with both watchdogs.

        Raises:
            BaseException: the driver's own error (a deadlock, a stall), or a stop from
                outside, unwrapped.
        """
        failure: BaseException | None = None
        with ClockWatch(self.runtime.kernel, _WARN_AFTER, self.watchdog):
            async with anyio.create_task_group() as host:
                host.start_soon(self.watch, name="fleet_async watchdog")
                try:
                    with self.scope:
                        await self.drive()
                except BaseException as exc:  # re-raised below, unwrapped
                    failure = exc  # the driver's own error, or a stop from outside
                finally:
                    host.cancel_scope.cancel()
        failure = failure or self.stalled
        if failure is not None:
            raise failure

    def is_host_cancel(self, exc: BaseException) -> bool:
        """Whether ``exc``, coming out of a mission's non-sim await, is the host loop
        cancelling the run (rather than, on asyncio, a future some library cancelled)."""
        if not isinstance(exc, self._cancel_exc):
            return False
        if self.scope.cancel_called:
            return True
        try:
            task = asyncio.current_task()
        except RuntimeError:  # trio: its Cancelled only ever means a real cancellation
            return True
        cancelling = getattr(task, "cancelling", None)
        return cancelling is None or cancelling() > 0  # Python 3.10 cannot tell: the host

    async def drive(self) -> None:
        """The loop: events due now, then the end test, then the clock."""
        runtime, kernel, sim = self.runtime, self.runtime.kernel, self.runtime.sim
        rtf = sim.params.target_rtf
        wall0, step0 = _wall_clock(), sim.step_count
        dt = sim.params.timestep
        checkpoint_at = time.perf_counter() + _YIELD_EVERY
        while True:
            if self.until_step is not None and kernel.now >= self.until_step:
                if self.then == "cancel":
                    await self._cancel_at_until()
                return
            await dispatch(kernel)
            if anyio.current_effective_deadline() == -math.inf and not self.scope.cancel_called:
                runtime.root.fail(_anyio_scope_misuse(kernel))
                continue  # the missions' cancellations are due at once; no checkpoint first
            if self._over():
                return
            stuck = kernel.nothing_due() and not runtime.step_driven()
            if stuck and self.until_step is None and rtf <= 0:
                if self._deadlocked():
                    return
            elif self.until_step is None and rtf <= 0 and self._watch_predicates():
                return
            before = sim.step_count
            self._advance()
            if sim.step_count == before:
                raise RuntimeError(
                    "the simulation did not advance (is it paused?): missions wait on sim "
                    "time, so sim.resume() it before awaiting"
                )
            if rtf > 0:  # pacing wraps the loop; missions never see wall time
                ahead = (sim.step_count - step0) * dt / rtf - (_wall_clock() - wall0)
                if ahead > 0:
                    await _wall_sleep(ahead)
                    checkpoint_at = time.perf_counter() + _YIELD_EVERY
            if time.perf_counter() >= checkpoint_at:  # behind real time, or unpaced
                await anyio.lowlevel.checkpoint()
                checkpoint_at = time.perf_counter() + _YIELD_EVERY

    def _over(self) -> bool:
        """Whether the run is over after this step's events: the ``until`` event was
        processed, or no mission is left and nothing asks the clock to go on."""
        event = self.until_event
        if event is not None:
            return event.processed
        if self.runtime.kernel.missions:
            return False
        return self.until_step is None or self.then == "cancel"

    def _deadlocked(self) -> bool:
        """Nothing will ever wake the missions left: raise, or return True to end the run
        (``on_deadlock="return"``, or no mission left).

        Raises:
            MissionDeadlockError: see ``fleet_async.run``.
        """
        kernel = self.runtime.kernel
        if self.until_event is not None:
            raise _deadlock(
                self.runtime, f"the run waits for {self.until_event!r}, which can no longer come"
            )
        if not kernel.missions:
            return True
        if self.on_deadlock == "return":
            return True
        raise _deadlock(
            self.runtime,
            "nothing will ever wake them (no timer is due, no action or predicate is pending)",
        )

    def _watch_predicates(self) -> bool:
        """Count the steps in which missions wait on predicates alone while the simulation
        stays idle; past PREDICATE_PATIENCE_S it is a deadlock (see there): raise, or return
        True to end the run (``on_deadlock="return"``).

        Raises:
            MissionDeadlockError: see ``fleet_async.run``.
        """
        runtime, sim = self.runtime, self.runtime.sim
        only_predicates = (
            runtime.kernel.nothing_due()
            and runtime.watches_predicates()
            and not runtime.step_driven(besides_predicates=True)
        )
        if not only_predicates or sim.idle_steps(1) < 1:
            self._idle_predicate_steps = 0
            return False
        self._idle_predicate_steps += 1
        if self._idle_predicate_steps * sim.params.timestep < PREDICATE_PATIENCE_S:
            return False
        self._idle_predicate_steps = 0
        if self.on_deadlock == "return" and self.until_event is None:
            return True
        raise _deadlock(
            runtime,
            f"they wait on sim.wait_until predicates that stayed false for "
            f"{PREDICATE_PATIENCE_S:.0f} s of sim time while nothing in the simulation moved "
            "and no timer was due (to wait for a time, use sim.sleep_until)",
        )

    def _advance(self) -> None:
        """Run the next step, or jump over every step before the next due event at once when
        the simulation says they are empty (nothing moves, nothing is due: the clock and the
        schedules advance exactly as if they had run). A predicate that a mission waits on
        is checked after every step, so it keeps the steps. A paced run jumps at most
        ``_YIELD_EVERY`` wall seconds' worth at a time, so the outside world is still served
        between jumps."""
        runtime, kernel, sim = self.runtime, self.runtime.kernel, self.runtime.sim
        gap = kernel.steps_to_next()
        if gap is None:  # missions wait on actions only: the simulation knows their timers
            gap = max(1, int(_JUMP_LIMIT_S / sim.params.timestep))
        if self.until_step is not None:
            left = self.until_step - kernel.now
            gap = min(gap, left)
        rtf = sim.params.target_rtf
        if rtf > 0:  # paced: jump no further than the outside world waits
            gap = min(gap, max(1, int(_YIELD_EVERY * rtf / sim.params.timestep)))
        skippable = gap > 0 and not runtime.watches_predicates()
        if skippable and sim.skip_idle_steps(gap):
            kernel.now = sim.step_count
            return
        runtime.step()

    async def _cancel_at_until(self) -> None:
        """``then="cancel"``: cancel every mission; let their cleanup run at this step (no
        more steps). The events that were due at this step are not processed."""
        runtime, kernel = self.runtime, self.runtime.kernel
        kernel.drop_due()
        runtime.root.cancel_scope.cancel()
        await dispatch(kernel)
        if kernel.missions:
            runtime.close_missions("run(until=..., then='cancel') was reached")

    async def watch(self) -> None:
        """The watchdog of non-sim awaits: fails the run when a mission holds the clock on
        one too long (a mission running Python code is the ClockWatch thread's)."""
        try:
            await self._watch_holds()
        except self._cancel_exc:  # stopped from outside (Ctrl-C, a host scope): stop the run
            self.scope.cancel()
            raise

    async def _watch_holds(self) -> None:
        kernel = self.runtime.kernel
        period = min(0.25, self.watchdog / 4)
        warned = False
        while True:
            await anyio.sleep(period)
            mission = kernel.holding
            if mission is None:
                continue
            held = time.perf_counter() - kernel.holding_since
            if not warned and self.watchdog > _WARN_AFTER and held >= _WARN_AFTER:
                warned = True
                warnings.warn(_hold_message(mission, kernel.holding_what, held), stacklevel=1)
            if held > self.watchdog:
                self.stalled = MissionStalledError(
                    _hold_message(mission, kernel.holding_what, held)
                    + f" (the watchdog allows {self.watchdog} s)"
                )
                self.scope.cancel()
                return


def _hold_message(mission: Mission, what: Any, held: float) -> str:
    return (
        f"mission {mission.name!r} has held the simulation clock for {held:.1f} s of wall time, "
        f"awaiting {what!r}, which is not a sim-time await: a wall-clock sleep "
        "(anyio.sleep, asyncio.sleep, trio.sleep), an anyio / asyncio / trio Lock, Event, "
        "Semaphore or queue, or real I/O. Inside missions use the sim-time versions: "
        "sim.sleep, sim.move_on_after, fleet_async.Event, Lock, Resource, Store"
    )


def _anyio_scope_misuse(kernel: Any) -> NoMissionRuntimeError:
    return NoMissionRuntimeError(
        f"at sim time {kernel.now * kernel.timestep:.3f} s a mission cancelled an anyio cancel "
        "scope that a mission had entered (anyio.CancelScope, anyio.move_on_after, "
        "anyio.fail_after): anyio's scopes belong to the host event loop and measure wall "
        "time, so they cannot cancel sim-time awaits. In missions use sim.cancel_scope(), "
        "sim.move_on_after() / sim.fail_after(), or mission.cancel()"
    )


def _deadlock(runtime: Runtime, why: str) -> MissionDeadlockError:
    kernel = runtime.kernel
    waits = [f"{m.name} on {m.target!r}" for m in sorted(kernel.missions, key=_by_key)]
    return MissionDeadlockError(
        f"deadlock at sim time {kernel.now * kernel.timestep:.3f} s: missions are alive but "
        f"{why}: " + "; ".join(waits)
    )


def _by_key(mission: Mission) -> tuple[int, ...]:
    return mission.key
