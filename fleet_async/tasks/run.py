"""Entry points: run missions against a simulation, inside anyio.

The driver (``fleet_async.tasks.driver``) alternates two things: process the events due at the
current step (resuming missions one at a time, in the kernel's order), then run one simulation
step. It runs inside an anyio host loop (asyncio or trio) only so that missions can await real
I/O: such an await is forwarded to the host loop and holds the clock until it returns.

How a run ends (SimPy's model, with deadlock detection as an option):

- without ``until``: when no mission is left (or, with ``on_deadlock="return"``, when the
  missions left can never wake);
- ``until=t``: before the events due at ``t``, with the clock at ``t`` even when every mission
  ended earlier. The missions still alive stay where they wait (``then="suspend"``, the
  default): ``fleet_async.run(sim, until=t2)`` continues them exactly, and
  ``sim.end_missions()`` ends them. ``then="cancel"`` cancels them at ``t`` instead (their
  cleanup runs at ``t``) and returns as soon as none is left, as the scenario runner, sweeps
  and the pytest plugin want;
- ``until=event``: once the kernel processed that event (a mission's end, a timer); the run
  returns its value.
"""

from __future__ import annotations

import importlib.util
import math
import sys
import threading
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

import anyio

from fleet_async.core.missions import frozen_heap, steps_for
from fleet_async.tasks.driver import Driver
from fleet_async.tasks.groups import lone_error
from fleet_async.tasks.kernel import SimEvent
from fleet_async.tasks.runtime import Runtime

if sys.version_info < (3, 11):  # pragma: no cover  # anyio brings the backport
    from exceptiongroup import BaseExceptionGroup

if TYPE_CHECKING:
    from fleet_async.core.missions import MissionSim

__all__ = ["run", "run_async"]

_THEN = ("suspend", "cancel")
_ON_DEADLOCK = ("raise", "return")


def run(
    sim: MissionSim,
    main: Callable[..., Awaitable[Any]] | None = None,
    *args: Any,
    until: float | SimEvent | None = None,
    then: str = "suspend",
    on_deadlock: str = "raise",
    backend: str = "asyncio",
    watchdog: float = 30.0,
) -> Any:
    """Run ``main(*args)`` as a mission (and the missions already waiting), stepping ``sim``
    whenever no mission is due.

    Args:
        sim: The simulation; its step loop is the only clock.
        main: Async function; it may start more missions (``sim.task_group()``,
            ``sim.spawn()``). None continues the missions a run left waiting (and those
            spawned before the run).
        *args: Passed to ``main``.
        until: Stop at this sim time (s), before the events due then (a time at or before
            the current one is an error), or once this event (a mission, a timer, an Event)
            has been processed.
        then: What ``until`` does to the missions still alive: "suspend" (the default,
            SimPy's) leaves them waiting for the next run; "cancel" cancels them at that
            time (their cleanup runs then) and ends the run early when none is left.
        on_deadlock: When missions are alive but nothing will ever wake them: "raise" (the
            default: in a fleet this is almost always a bug, and a silent return would hide
            it) raises MissionDeadlockError naming what each waits on; "return" returns, as
            SimPy does, leaving them waiting.
        backend: The anyio host loop, "asyncio" or "trio" (the missions run the same on both).
        watchdog: Wall seconds a mission may hold the clock (a non-sim await, or Python code
            that never awaits) before MissionStalledError; a warning names it after 1 s.

    Returns:
        What ``main`` returned; the event's value for ``until=event``; None when ``main`` was
        cancelled, had not returned when ``until`` came, or was not given.

    Raises:
        BaseException: a mission's failure, as itself when it is the only one (with the
            mission's name and the sim time in its notes); several concurrent failures as an
            ExceptionGroup. A failed event that nobody waited on (and nobody defused), with
            a note naming it. The run stops at the sim time of the failure: the other
            missions are cancelled then, their cleanup runs at that time, and what still
            waits is closed.
        MissionDeadlockError: missions are alive and nothing will ever wake them (see
            ``on_deadlock``; always for ``until=event`` when the event can no longer come),
            including missions that wait on a ``sim.wait_until`` predicate while nothing in
            the simulation changes.
        MissionStalledError: a mission held the clock longer than ``watchdog``.
        ValueError: a bad ``until``, ``then``, ``on_deadlock`` or ``backend``.
        RuntimeError: if a run is already in progress on ``sim``.
        ModuleNotFoundError: ``backend="trio"`` where trio is not installed (the message says
            how to install it).
    """
    if backend not in ("asyncio", "trio"):
        raise ValueError(f'fleet_async.run: backend must be "asyncio" or "trio", got {backend!r}')
    if backend == "trio" and importlib.util.find_spec("trio") is None:
        raise ModuleNotFoundError(
            'fleet_async.run(backend="trio") needs trio, which is not installed: '
            'python -m pip install -e ".[trio]" (from a clone)',
            name="trio",
        )
    options = dict(until=until, then=then, on_deadlock=on_deadlock, watchdog=watchdog)
    try:
        return anyio.run(_run_with_kwargs, sim, main, args, options, backend=backend)
    except BaseExceptionGroup as group:  # the host loop's own wrapping of a lone Ctrl-C
        lone = lone_error(group)
        if isinstance(lone, KeyboardInterrupt):
            raise lone from None
        raise


async def _run_with_kwargs(
    sim: MissionSim,
    main: Callable[..., Awaitable[Any]] | None,
    args: tuple[Any, ...],
    options: dict[str, Any],
) -> Any:
    return await run_async(sim, main, *args, **options)


async def run_async(
    sim: MissionSim,
    main: Callable[..., Awaitable[Any]] | None = None,
    *args: Any,
    until: float | SimEvent | None = None,
    then: str = "suspend",
    on_deadlock: str = "raise",
    watchdog: float = 30.0,
) -> Any:
    """:func:`run` for code already inside an anyio event loop (asyncio or trio).

    If the run is stopped from outside (its host scope cancelled, Ctrl-C), the missions still
    alive are closed (their ``finally`` blocks run) before the cancellation propagates.
    """
    if then not in _THEN:
        raise ValueError(f'fleet_async.run: then must be "suspend" or "cancel", got {then!r}')
    if on_deadlock not in _ON_DEADLOCK:
        raise ValueError(
            f'fleet_async.run: on_deadlock must be "raise" or "return", got {on_deadlock!r}'
        )
    if not watchdog > 0:  # also rejects NaN
        raise ValueError(f"watchdog must be a positive number of wall seconds, got {watchdog!r}")
    runtime = Runtime.of(sim)
    if runtime.driving:
        raise RuntimeError("this simulation already runs missions (one fleet_async.run at a time)")
    runtime.touch()
    until_step, until_event = _until(runtime, until)
    main_mission = None
    if main is not None:
        main_mission = runtime.root.start(main, args, getattr(main, "__name__", "main"))
    driver = Driver(runtime, until_step, until_event, then, on_deadlock, watchdog)
    ended = True
    runtime.driving = True
    runtime.kernel.thread = threading.get_ident()
    runtime.kernel.is_host_cancel = driver.is_host_cancel
    try:
        with frozen_heap(sim.params.gc_freeze):
            await driver.run()
        # A run that fails ends its missions: they were cancelled with the run's root scope.
        ended = driver.ends_runtime() or bool(runtime.root.errors)
    finally:
        runtime.driving = False
        if ended:
            try:
                if runtime.kernel.missions:  # their cleanup may release resources
                    runtime.close_missions("the run stopped early")
            finally:
                runtime.close()
    errors = runtime.root.errors
    if len(errors) == 1:
        raise lone_error(errors[0])
    if errors:
        raise BaseExceptionGroup("several missions failed", errors)
    if until_event is not None:
        if not until_event.ok:
            raise until_event.raw_value
        return until_event.raw_value
    if main_mission is None or main_mission.is_alive or main_mission.cancelled:
        return None
    return main_mission.result()


def _until(runtime: Runtime, until: float | SimEvent | None) -> tuple[int | None, SimEvent | None]:
    """The step (or the event) ``until`` stops the run at.

    Raises:
        ValueError: for a time that is not finite or not after now, or an event of another
            simulation.
    """
    if until is None:
        return None, None
    kernel = runtime.kernel
    if isinstance(until, SimEvent):
        if until.kernel is not kernel and not until.rebind(kernel):
            raise ValueError(f"fleet_async.run: until={until!r} belongs to another simulation")
        return None, until
    if isinstance(until, bool) or not isinstance(until, (int, float)) or not math.isfinite(until):
        raise ValueError(
            f"fleet_async.run: until must be a finite sim time (s) or a sim event, got {until!r}"
        )
    step = steps_for(until, kernel.timestep)
    if step <= kernel.now:
        raise ValueError(
            f"fleet_async.run: until={until!r} must be later than the current sim time "
            f"({kernel.now * kernel.timestep!r} s)"
        )
    return step, None
