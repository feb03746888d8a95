"""The sim-time awaitables the simulation offers to async missions.

The mission runtime lives in ``fleet_async.tasks``; the core never imports it. The first
mission call on a simulation makes its runtime (through the mission layer's hook) and installs
it with ``sim.set_mission_runtime``; these methods delegate to it. The runtime outlives a run
that stops at ``until`` with missions still waiting, so the next ``fleet_async.run`` continues
them, and things made before a run (timers, events, requests, missions) start when it starts
(SimPy's model). ``sim.end_missions()`` ends what is left.

Most of these return an *event* rather than being coroutines: ``sim.sleep(2.0)`` schedules a
timer when it is called (SimPy's ``env.timeout``), and ``await`` waits for it. Events compose:
``await sim.any_of(a, b)``, ``await (req | sim.timeout(5))``.

Never use ``anyio.sleep`` / ``anyio.move_on_after`` to wait inside a mission: they are wall-clock
waits that hold the simulation clock (or break determinism). Use ``sim.sleep`` and
``sim.move_on_after``, which are measured in sim time.
"""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable, Iterable
from typing import TYPE_CHECKING, Any, Protocol

from fleet_async.core.base.events import EventBus
from fleet_async.core.missions.hooks import mission_hook

if TYPE_CHECKING:
    from fleet_async.core.actions.action import Action

__all__ = ["MissionRuntime", "SimEventBus", "SimMissionApi"]

logger = logging.getLogger(__name__)


class MissionRuntime(Protocol):
    """What the core needs from a mission runtime (``fleet_async.tasks.runtime.Runtime``)."""

    driving: bool

    def timeout(self, seconds: float, value: Any = ..., what: str = ...) -> Any: ...
    def sleep_until(self, t: float) -> Any: ...
    def scope(
        self, seconds: float | None, fail: bool, shield: bool = ..., absolute: bool = ...
    ) -> Any: ...
    def wait_action(
        self, agent: Any, action: Action, detached: bool = ..., what: str = ...
    ) -> Any: ...
    def wait_until(self, predicate: Callable[[], bool]) -> Any: ...
    def wait_event(self, name: str, where: Callable[..., bool] | None) -> Any: ...
    def event_stream(self, name: str, where: Callable[..., bool] | None) -> Any: ...
    def task_group(self) -> Any: ...
    def gather(self, *items: Any) -> Awaitable[list[Any]]: ...
    def race(self, *items: Any) -> Awaitable[tuple[int, Any]]: ...
    def spawn(self, fn: Any, *args: Any, name: str | None) -> Any: ...
    def any_of(self, events: Iterable[Any]) -> Any: ...
    def all_of(self, events: Iterable[Any]) -> Any: ...
    def event(self) -> Any: ...
    def current_mission(self, what: str) -> Any: ...
    def mission_rng(self) -> Any: ...
    def touch(self) -> None: ...
    def mission_names(self) -> list[str]: ...
    def end(self) -> None: ...


def _events(events: tuple[Any, ...]) -> Iterable[Any]:
    """``any_of(a, b)`` and ``any_of([a, b])`` alike."""
    if len(events) == 1 and not hasattr(events[0], "__await__"):
        return tuple(events[0])
    return events


class SimMissionApi:
    """Mixin for MultiRobotSimulationCore: sim-time waits for missions."""

    _mission_runtime: MissionRuntime | None = None

    def set_mission_runtime(self, runtime: MissionRuntime | None) -> None:
        """Install (or remove, with None) the runtime that serves sim-time awaits."""
        if runtime is not None and self._mission_runtime not in (None, runtime):
            raise RuntimeError("this simulation has a mission runtime already")
        self._mission_runtime = runtime

    @property
    def mission_runtime(self) -> MissionRuntime | None:
        """The simulation's mission runtime, or None before the first mission call (and
        after ``end_missions()``)."""
        return self._mission_runtime

    def ensure_mission_runtime(self) -> MissionRuntime:
        """The mission runtime, made and installed on first use (the mission layer's
        ``"mission_runtime"`` hook), its clock brought to the current step outside runs.

        Raises:
            RuntimeError: if the mission layer is not loaded (``import fleet_async.tasks``).
        """
        runtime = self._mission_runtime
        if runtime is None:
            runtime = mission_hook("mission_runtime")(self)
            self._mission_runtime = runtime
        runtime.touch()
        return runtime

    def _runtime(self, what: str) -> MissionRuntime:
        runtime = self._mission_runtime
        if runtime is None:
            return self.ensure_mission_runtime()
        runtime.touch()
        return runtime

    def suspended_missions(self) -> list[str]:
        """Names of the missions alive between runs (a run stopped at ``until`` with them
        waiting), in start order; empty when none are."""
        runtime = self._mission_runtime
        return [] if runtime is None else runtime.mission_names()

    def end_missions_before_close(self) -> None:
        """``end_missions()`` as the simulation closes: their cleanup runs now; a failure
        of it is logged, so that closing goes on."""
        runtime = self._mission_runtime
        if runtime is None or runtime.driving:
            return
        try:
            runtime.end()
        except Exception:
            logger.exception("a mission failed while ending with its simulation")

    def end_missions(self) -> None:
        """End the missions left waiting by ``fleet_async.run(..., until=t)``: each is
        cancelled at the current sim time (its ``finally`` blocks run; sim awaits in them are
        served at this step, without stepping), their queued requests are withdrawn and their
        unfinished actions cancelled. The runtime is dropped; the next mission call makes a
        fresh one.

        Raises:
            RuntimeError: during a run (cancel the missions from inside it instead).
        """
        runtime = self._mission_runtime
        if runtime is not None:
            runtime.end()

    @property
    def now(self) -> float:
        """The sim time in seconds (SimPy's ``env.now``; the same as ``sim_time``)."""
        now: float = self.sim_time  # type: ignore[attr-defined]  # mixed into the simulation
        return now

    # ----- time ---------------------------------------------------------------------------

    def sleep(self, seconds: float) -> Any:
        """``await sim.sleep(s)``: wait ``s`` seconds of sim time, rounded up to whole steps
        (``sleep(0)`` yields to the missions due now, as SimPy's ``timeout(0)``).

        Raises:
            ValueError: if ``seconds`` is negative or not finite.
        """
        return self._runtime("sim.sleep").timeout(seconds, None, "sim.sleep")

    def timeout(self, delay: float, value: Any = None) -> Any:
        """SimPy's ``env.timeout``: an event that succeeds with ``value`` after ``delay``
        seconds of sim time (scheduled now, awaited whenever)."""
        return self._runtime("sim.timeout").timeout(delay, value, "sim.timeout")

    def sleep_until(self, t: float) -> Any:
        """``await sim.sleep_until(t)``: wait until sim time ``t`` (s); at once if past."""
        return self._runtime("sim.sleep_until").sleep_until(t)

    def move_on_after(self, seconds: float | None, shield: bool = False) -> Any:
        """A cancel scope that gives up after ``seconds`` of sim time (anyio's shape:
        ``cancelled_caught``, ``cancel()``, ``shield``, ``deadline``)."""
        return self._runtime("sim.move_on_after").scope(seconds, fail=False, shield=shield)

    def fail_after(self, seconds: float | None, shield: bool = False) -> Any:
        """Like :meth:`move_on_after` but raises TimeoutError when the deadline passes."""
        return self._runtime("sim.fail_after").scope(seconds, fail=True, shield=shield)

    def move_on_at(self, t: float, shield: bool = False) -> Any:
        """A cancel scope that gives up at sim time ``t``."""
        return self._runtime("sim.move_on_at").scope(t, fail=False, shield=shield, absolute=True)

    def fail_at(self, t: float, shield: bool = False) -> Any:
        """Like :meth:`move_on_at` but raises TimeoutError at the deadline."""
        return self._runtime("sim.fail_at").scope(t, fail=True, shield=shield, absolute=True)

    def cancel_scope(self, shield: bool = False) -> Any:
        """A cancel scope without a deadline: ``with sim.cancel_scope(shield=True):`` protects
        cleanup that awaits sim time (use it instead of ``anyio.CancelScope`` in missions)."""
        return self._runtime("sim.cancel_scope").scope(None, fail=False, shield=shield)

    def wait_until(self, predicate: Callable[[], bool]) -> Any:
        """``await sim.wait_until(pred)``: wait until ``pred()`` is true, checked now and at the
        end of every step."""
        return self._runtime("sim.wait_until").wait_until(predicate)

    # ----- missions and events ------------------------------------------------------------------

    def task_group(self) -> Any:
        """A task group whose children are missions: ``async with sim.task_group() as tg``."""
        return self._runtime("sim.task_group").task_group()

    def spawn(self, fn: Any, *args: Any, name: str | None = None) -> Any:
        """Start ``fn(*args)`` as a mission of the run itself (SimPy's ``env.process``); it
        runs until it ends or the run stops. Returns its handle."""
        return self._runtime("sim.spawn").spawn(fn, *args, name=name)

    def gather(self, *missions: Any) -> Awaitable[list[Any]]:
        """Run missions (async callables, coroutines or events) concurrently; results in
        order. A lone failure is raised as itself."""
        return self._runtime("sim.gather").gather(*missions)

    def race(self, *missions: Any) -> Awaitable[tuple[int, Any]]:
        """Run missions concurrently; return (index, result) of the first to finish.

        The losers are cancelled, and so are the actions they were waiting on.
        """
        return self._runtime("sim.race").race(*missions)

    def any_of(self, *events: Any) -> Any:
        """An event that triggers when the first of ``events`` has; its value maps each event
        processed by then to its value."""
        return self._runtime("sim.any_of").any_of(_events(events))

    def all_of(self, *events: Any) -> Any:
        """An event that triggers when all of ``events`` have; its value maps each to its
        value."""
        return self._runtime("sim.all_of").all_of(_events(events))

    def event(self) -> Any:
        """A new one-shot event (``fleet_async.Event(sim)``)."""
        return self._runtime("sim.event").event()

    @property
    def active_mission(self) -> Any:
        """The mission running now (its handle).

        Raises:
            RuntimeError: outside a mission.
        """
        return self._runtime("sim.active_mission").current_mission("sim.active_mission")

    def mission_rng(self) -> Any:
        """A numpy Generator for the calling mission, derived from the seed and its spawn key."""
        return self._runtime("sim.mission_rng").mission_rng()


class SimEventBus(EventBus):
    """The simulation's event bus, which missions can also ``await`` events on."""

    __slots__ = ("_owner",)

    def __init__(self, owner: SimMissionApi, on_error: str = "raise") -> None:
        super().__init__(on_error)
        self._owner = owner

    def wait(self, name: str, where: Callable[..., bool] | None = None) -> Any:
        """``await sim.events.wait(name, where)``: the next ``name`` event whose payload
        ``where(**payload)`` accepts, as a dict."""
        return self._owner.ensure_mission_runtime().wait_event(name, where)

    def stream(self, name: str, where: Callable[..., bool] | None = None) -> Any:
        """An async iterator over every ``name`` event from now on (``where`` filters)::

        async with sim.events.stream("collision_started") as collisions:
            async for payload in collisions:
                ...
        """
        return self._owner.ensure_mission_runtime().event_stream(name, where)
