"""Entry points: run missions against a simulation inside anyio."""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

import anyio

from fleet_async.tasks.runtime import Runtime

if TYPE_CHECKING:
    from fleet_async.core.missions import MultiRobotSimulationCore

__all__ = ["run", "run_async"]

# Pacing's view of the wall: module attributes so tests can run pacing on a fake clock.
_wall_clock = time.perf_counter
_wall_sleep = anyio.sleep


def _backend_name() -> str:
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return "trio"
    return "asyncio"


def run(
    sim: MultiRobotSimulationCore,
    main: Callable[..., Awaitable[Any]],
    *args: Any,
    until: float | None = None,
    backend: str = "asyncio",
    watchdog: float = 30.0,
) -> Any:
    """Run ``main(*args)`` as a mission, stepping ``sim`` whenever every mission is parked.

    Args:
        sim: The simulation; its step loop is the only clock.
        main: Async function; it may spawn more missions with ``sim.task_group()``.
        *args: Passed to ``main``.
        until: Stop (cancelling every mission) once sim time reaches this many seconds.
        backend: anyio backend, "asyncio" or "trio".
        watchdog: Wall seconds a mission may hold the clock (an I/O or wall-clock wait)
            before MissionStalledError.

    Returns:
        What ``main`` returned, or None when stopped by ``until``.
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
    """:func:`run` for code already inside an event loop (asyncio or trio)."""
    if not watchdog > 0:  # also rejects NaN
        raise ValueError(f"watchdog must be a positive number of wall seconds, got {watchdog!r}")
    runtime = Runtime(sim, _backend_name(), watchdog)
    sim.set_mission_runtime(runtime)
    until_step = None if until is None else math.ceil(until / sim.params.timestep - 1e-9)
    rtf = sim.params.target_rtf
    wall0, sim0 = _wall_clock(), sim.sim_time
    box: list[Any] = []
    try:
        async with anyio.create_task_group() as tg:
            runtime.spawn(tg, main, args, (0,), getattr(main, "__name__", "main"), box=box)
            tg.start_soon(runtime.watch, name="fleet_async watchdog")
            await runtime.settle()
            while True:
                if runtime.alive == 0:
                    tg.cancel_scope.cancel()  # the watchdog
                    break
                if until_step is not None and sim.step_count >= until_step:
                    tg.cancel_scope.cancel()
                    break
                runtime.check_deadlock()
                sim.step_once()
                await runtime.after_step()  # ends settled
                if rtf > 0:  # pacing wraps the loop; missions never see wall time
                    ahead = (sim.sim_time - sim0) / rtf - (_wall_clock() - wall0)
                    if ahead > 0:
                        await _wall_sleep(ahead)
                        # the outside world ran meanwhile and may have woken missions (a
                        # sim Event set, a cancel): deliver that before the next step
                        await runtime.settle()
    finally:
        sim.set_mission_runtime(None)
        runtime.close()
    return box[0] if box else None
