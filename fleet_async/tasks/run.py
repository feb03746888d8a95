"""Entry points: run missions against a simulation, inside anyio.

The driver alternates two things until every mission has ended: process the events due at the
current step (resuming missions one at a time, in the kernel's order), then run one simulation
step. It runs inside an anyio host loop (asyncio or trio) only so that missions can await real
I/O: such an await is forwarded to the host loop and holds the clock until it returns. A
watchdog task beside the driver turns a hold longer than ``watchdog`` wall seconds into
MissionStalledError, and warns once after a second.
"""

from __future__ import annotations

import logging
import math
import sys
import time
import warnings
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

import anyio
import anyio.lowlevel

from fleet_async.tasks.errors import MissionDeadlockError, MissionStalledError
from fleet_async.tasks.groups import lone_error
from fleet_async.tasks.missions import dispatch
from fleet_async.tasks.runtime import Runtime

if sys.version_info < (3, 11):  # pragma: no cover  # anyio brings the backport
    from exceptiongroup import BaseExceptionGroup

if TYPE_CHECKING:
    from fleet_async.core.missions import MultiRobotSimulationCore
    from fleet_async.tasks.missions import Mission

__all__ = ["run", "run_async"]

logger = logging.getLogger(__name__)

# Pacing's view of the wall: module attributes so tests can run pacing on a fake clock.
_wall_clock = time.perf_counter
_wall_sleep = anyio.sleep

_YIELD_EVERY = 0.05
"""Wall seconds between the driver's checkpoints on the host loop when it is not paced, so
other tasks of the host loop (a live viewer, a server) keep running."""
_WARN_AFTER = 1.0
"""Wall seconds a mission may hold the clock before one warning says so."""


def run(
    sim: MultiRobotSimulationCore,
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
        What ``main`` returned, or None when stopped by ``until`` before it returned.

    Raises:
        BaseException: a mission's failure, as itself when it is the only one (with the
            mission's name and the sim time in its notes); several concurrent failures as an
            ExceptionGroup.
        MissionDeadlockError: missions are alive, no event is due ever and stepping cannot
            help (without ``until``).
        MissionStalledError: a mission held the clock longer than ``watchdog``.
    """
    return anyio.run(_run_with_kwargs, sim, main, args, until, watchdog, backend=backend)


async def _run_with_kwargs(
    sim: MultiRobotSimulationCore,
    main: Callable[..., Awaitable[Any]],
    args: tuple[Any, ...],
    until: float | None,
    watchdog: float,
) -> Any:
    return await run_async(sim, main, *args, until=until, watchdog=watchdog)


async def run_async(
    sim: MultiRobotSimulationCore,
    main: Callable[..., Awaitable[Any]],
    *args: Any,
    until: float | None = None,
    watchdog: float = 30.0,
) -> Any:
    """:func:`run` for code already inside an anyio event loop (asyncio or trio)."""
    if not watchdog > 0:  # also rejects NaN
        raise ValueError(f"watchdog must be a positive number of wall seconds, got {watchdog!r}")
    if until is not None and not math.isfinite(until):
        raise ValueError(f"until must be a finite sim time, got {until!r}")
    runtime = Runtime(sim)
    sim.set_mission_runtime(runtime)
    kernel = runtime.kernel
    kernel.host_cancel = anyio.get_cancelled_exc_class()
    until_step = None if until is None else math.ceil(until / sim.params.timestep - 1e-9)
    driver = _Driver(runtime, until_step, watchdog)
    try:
        main_mission = runtime.root.start(main, args, getattr(main, "__name__", "main"))
        failure: Exception | None = None
        async with anyio.create_task_group() as host:
            host.start_soon(driver.watch, name="fleet_async watchdog")
            try:
                with driver.scope:
                    await driver.drive()
            except Exception as exc:  # the driver's own errors (a deadlock)
                failure = exc
            finally:
                host.cancel_scope.cancel()
        failure = failure or driver.stalled
        if failure is not None:
            _close_missions(runtime, f"the run failed: {failure}")
            raise failure
    finally:
        sim.set_mission_runtime(None)
        runtime.close()
    errors = runtime.root.errors
    if len(errors) == 1:
        raise lone_error(errors[0])
    if errors:
        raise BaseExceptionGroup("several missions failed", errors)
    if driver.stopped_by_until or main_mission.cancelled:
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
        self.stopped_by_until = False

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
            if self.until_step is None and not kernel.queue and not runtime.step_driven():
                raise _deadlock(runtime)
            before = sim.step_count
            runtime.step()
            if sim.step_count == before:
                raise RuntimeError(
                    "the simulation did not advance (is it paused?): missions wait on sim "
                    "time, so sim.resume() it before awaiting"
                )
            if rtf > 0:  # pacing wraps the loop; missions never see wall time
                ahead = (sim.step_count - step0) * dt / rtf - (_wall_clock() - wall0)
                if ahead > 0:
                    await _wall_sleep(ahead)
            elif time.perf_counter() >= checkpoint_at:
                await anyio.lowlevel.checkpoint()
                checkpoint_at = time.perf_counter() + _YIELD_EVERY

    async def _stop_at_until(self) -> None:
        """Cancel every mission; let their cleanup run at this step (no more steps)."""
        self.stopped_by_until = True
        kernel = self.runtime.kernel
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
