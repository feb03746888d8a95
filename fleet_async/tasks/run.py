"""Entry points: run missions against a simulation, inside anyio.

The driver alternates two things until every mission has ended: process the events due at the
current step (resuming missions one at a time, in the kernel's order), then run one simulation
step. It runs inside an anyio host loop (asyncio or trio) only so that missions can await real
I/O: such an await is forwarded to the host loop and holds the clock until it returns. A
watchdog task beside the driver turns a hold longer than ``watchdog`` wall seconds into
MissionStalledError, and warns once after a second.
"""

from __future__ import annotations

import asyncio
import importlib.util
import logging
import math
import sys
import time
import warnings
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

import anyio
import anyio.lowlevel

from fleet_async.core.missions import steps_for
from fleet_async.tasks.errors import MissionDeadlockError, MissionStalledError
from fleet_async.tasks.groups import lone_error
from fleet_async.tasks.missions import dispatch
from fleet_async.tasks.runtime import Runtime

if sys.version_info < (3, 11):  # pragma: no cover  # anyio brings the backport
    from exceptiongroup import BaseExceptionGroup

if TYPE_CHECKING:
    from fleet_async.core.missions import MissionSim
    from fleet_async.tasks.missions import Mission

__all__ = ["run", "run_async"]

logger = logging.getLogger(__name__)

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


def run(
    sim: MissionSim,
    main: Callable[..., Awaitable[Any]],
    *args: Any,
    until: float | None = None,
    backend: str = "asyncio",
    watchdog: float = 30.0,
) -> Any:
    """Run ``main(*args)`` as a mission, stepping ``sim`` whenever no mission is due.

    Args:
        sim: The simulation; its step loop is the only clock.
        main: Async function; it may start more missions (``sim.task_group()``,
            ``sim.spawn()``).
        *args: Passed to ``main``.
        until: Stop at this sim time (s): the events due then are not processed, every
            mission still alive is cancelled, and its cleanup runs at that time.
        backend: The anyio host loop, "asyncio" or "trio" (the missions run the same on both).
        watchdog: Wall seconds a mission may hold the clock on a non-sim await (I/O, a
            wall-clock sleep) before MissionStalledError.

    Returns:
        What ``main`` returned (None if it was cancelled, or stopped by ``until`` before it
        returned).

    Raises:
        BaseException: a mission's failure, as itself when it is the only one (with the
            mission's name and the sim time in its notes); several concurrent failures as an
            ExceptionGroup.
        MissionDeadlockError: missions are alive, no event is due ever and stepping cannot
            help (without ``until``, and unpaced: with ``target_rtf`` > 0 the clock keeps
            running for the outside world to act).
        MissionStalledError: a mission held the clock longer than ``watchdog``.
        ValueError: ``backend`` is neither "asyncio" nor "trio".
        ModuleNotFoundError: ``backend="trio"`` where trio is not installed (the message says
            how to install it).
    """
    if backend not in ("asyncio", "trio"):
        raise ValueError(f'fleet_async.run: backend must be "asyncio" or "trio", got {backend!r}')
    if backend == "trio" and importlib.util.find_spec("trio") is None:
        raise ModuleNotFoundError(
            'fleet_async.run(backend="trio") needs trio, which is not installed: '
            'pip install "fleet-async[trio]"',
            name="trio",
        )
    try:
        return anyio.run(_run_with_kwargs, sim, main, args, until, watchdog, backend=backend)
    except BaseExceptionGroup as group:  # the host loop's own wrapping of a lone Ctrl-C
        lone = lone_error(group)
        if isinstance(lone, KeyboardInterrupt):
            raise lone from None
        raise


async def _run_with_kwargs(
    sim: MissionSim,
    main: Callable[..., Awaitable[Any]],
    args: tuple[Any, ...],
    until: float | None,
    watchdog: float,
) -> Any:
    return await run_async(sim, main, *args, until=until, watchdog=watchdog)


async def run_async(
    sim: MissionSim,
    main: Callable[..., Awaitable[Any]],
    *args: Any,
    until: float | None = None,
    watchdog: float = 30.0,
) -> Any:
    """:func:`run` for code already inside an anyio event loop (asyncio or trio).

    If the run is stopped from outside (its host scope cancelled, Ctrl-C), the missions still
    alive are closed (their ``finally`` blocks run) before the cancellation propagates.
    """
    if not watchdog > 0:  # also rejects NaN
        raise ValueError(f"watchdog must be a positive number of wall seconds, got {watchdog!r}")
    if until is not None and not math.isfinite(until):
        raise ValueError(f"until must be a finite sim time, got {until!r}")
    runtime = Runtime(sim)
    sim.set_mission_runtime(runtime)
    until_step = None if until is None else steps_for(until, sim.params.timestep)
    driver = _Driver(runtime, until_step, watchdog)
    runtime.kernel.is_host_cancel = driver.is_host_cancel
    try:
        main_mission = runtime.root.start(main, args, getattr(main, "__name__", "main"))
        failure: BaseException | None = None
        async with anyio.create_task_group() as host:
            host.start_soon(driver.watch, name="fleet_async watchdog")
            try:
                with driver.scope:
                    await driver.drive()
            except BaseException as exc:  # re-raised below, unwrapped
                failure = exc  # the driver's own error, or a stop from outside
            finally:
                host.cancel_scope.cancel()
        failure = failure or driver.stalled
        if failure is not None:
            raise failure
    finally:
        if runtime.kernel.missions:  # still installed: their cleanup may release resources
            _close_missions(runtime, "the run stopped early")
        sim.set_mission_runtime(None)
        runtime.close()
    errors = runtime.root.errors
    if len(errors) == 1:
        raise lone_error(errors[0])
    if errors:
        raise BaseExceptionGroup("several missions failed", errors)
    if main_mission.is_alive or main_mission.cancelled:
        return None
    return main_mission.result()


class _Driver:
    """Steps the simulation between event batches; paces; watches for stalls."""

    def __init__(self, runtime: Runtime, until_step: int | None, watchdog: float) -> None:
        self.runtime = runtime
        self.until_step = until_step
        self.watchdog = watchdog
        self.scope = anyio.CancelScope()
        self.stalled: MissionStalledError | None = None
        self._cancel_exc = anyio.get_cancelled_exc_class()

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
        runtime, kernel, sim = self.runtime, self.runtime.kernel, self.runtime.sim
        rtf = sim.params.target_rtf
        wall0, step0 = _wall_clock(), sim.step_count
        dt = sim.params.timestep
        checkpoint_at = time.perf_counter() + _YIELD_EVERY
        while True:
            if self.until_step is not None and kernel.now >= self.until_step:
                await self._stop_at_until()
                return
            await dispatch(kernel)
            if not kernel.missions:
                return
            stuck = kernel.nothing_due() and not runtime.step_driven()
            if stuck and self.until_step is None and rtf <= 0:
                raise _deadlock(runtime)
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

    async def _stop_at_until(self) -> None:
        """Cancel every mission; let their cleanup run at this step (no more steps). The
        events that were due at this step are not processed (SimPy's ``run(until=t)``)."""
        kernel = self.runtime.kernel
        kernel.drop_due()
        self.runtime.root.cancel_scope.cancel()
        await dispatch(kernel)
        if kernel.missions:
            _close_missions(self.runtime, "run(until=...) was reached")

    async def watch(self) -> None:
        """The watchdog: fails the run when a mission holds the clock too long."""
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


def _deadlock(runtime: Runtime) -> MissionDeadlockError:
    kernel = runtime.kernel
    waits = [f"{m.name} on {m.target!r}" for m in sorted(kernel.missions, key=_by_key)]
    return MissionDeadlockError(
        f"deadlock at sim time {kernel.now * kernel.timestep:.3f} s: missions are alive but "
        "nothing will ever wake them (no timer is due, no action or predicate is pending): "
        + "; ".join(waits)
    )


def _by_key(mission: Mission) -> tuple[int, ...]:
    return mission.key


def _close_missions(runtime: Runtime, why: str) -> None:
    """End the missions still alive without resuming them (their ``finally`` blocks run),
    the last started first, so that children end before the groups that wait for them."""
    missions = sorted(runtime.kernel.missions, key=_by_key)
    if missions:
        logger.warning("closing missions %s: %s", [m.name for m in missions], why)
    for mission in reversed(missions):
        mission.close()
