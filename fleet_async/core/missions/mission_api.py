"""The sim-time awaitables the simulation and its agents offer to async missions.

The mission runtime lives in ``fleet_async.tasks``; the core never imports it. A running
``fleet_async.run`` installs its runtime with ``sim.set_mission_runtime`` and these methods
delegate to it. Outside a run they raise a clear error.

Never use ``anyio.sleep`` / ``anyio.move_on_after`` to wait inside a mission: they are wall-clock
waits that hold the simulation clock (or break determinism). Use ``sim.sleep`` and
``sim.move_on_after``, which are measured in sim time.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any, Protocol

from fleet_async.core.base.events import EventBus

if TYPE_CHECKING:
    from fleet_async.core.actions.action import Action

__all__ = ["MissionRuntime", "SimEventBus", "SimMissionApi"]


class MissionRuntime(Protocol):
    """What the core needs from a mission runtime."""

    def steps_for(self, seconds: float) -> int: ...
    def sleep_steps(self, steps: int, what: str = ...) -> Awaitable[None]: ...
    def wait_action(self, action: Action, what: str) -> Awaitable[Action]: ...
    async def wait_until(self, predicate: Callable[[], bool], what: str = ...) -> None: ...
    async def wait_event(self, name: str, where: Callable[..., bool] | None) -> dict[str, Any]: ...
    def timeout(
        self, seconds: float, fail: bool, shield: bool = ..., absolute: bool = ...
    ) -> Any: ...
    def task_group(self) -> Any: ...
    async def gather(self, *items: Any) -> list[Any]: ...
    async def race(self, *items: Any) -> tuple[int, Any]: ...
    def mission_rng(self) -> Any: ...
    def event_stream(self, name: str, where: Callable[..., bool] | None) -> Any: ...


def _no_runtime(what: str) -> RuntimeError:
    return RuntimeError(
        f"{what} needs a running mission: start missions with fleet_async.run(sim, main) "
        "(or await fleet_async.tasks.run_async(sim, main) inside an event loop)"
    )


class SimMissionApi:
    """Mixin for MultiRobotSimulationCore: sim-time waits for missions."""

    _mission_runtime: MissionRuntime | None = None

    def set_mission_runtime(self, runtime: MissionRuntime | None) -> None:
        """Install (or remove, with None) the runtime that serves sim-time awaits."""
        if runtime is not None and self._mission_runtime is not None:
            raise RuntimeError(
                "this simulation already runs missions (one fleet_async.run at a time)"
            )
        self._mission_runtime = runtime

    @property
    def mission_runtime(self) -> MissionRuntime | None:
        """The runtime of the ``fleet_async.run`` in progress, or None."""
        return self._mission_runtime

    def _runtime(self, what: str) -> MissionRuntime:
        if self._mission_runtime is None:
            raise _no_runtime(what)
        return self._mission_runtime

    async def sleep(self, seconds: float) -> None:
        """Wait ``seconds`` of sim time (rounded up to whole steps; <= 0 just yields)."""
        runtime = self._runtime("sim.sleep")
        await runtime.sleep_steps(runtime.steps_for(seconds), "sim.sleep")

    async def sleep_until(self, t: float) -> None:
        """Wait until sim time ``t`` (s); returns at once if it has passed."""
        runtime = self._runtime("sim.sleep_until")
        now = self.sim_time  # type: ignore[attr-defined]  # mixed into MultiRobotSimulationCore
        await runtime.sleep_steps(runtime.steps_for(t - now), "sim.sleep_until")

    def move_on_after(self, seconds: float, shield: bool = False) -> Any:
        """A cancel scope that gives up after ``seconds`` of sim time (anyio semantics)."""
        return self._runtime("sim.move_on_after").timeout(seconds, fail=False, shield=shield)

    def fail_after(self, seconds: float, shield: bool = False) -> Any:
        """Like :meth:`move_on_after` but raises TimeoutError when the deadline passes."""
        return self._runtime("sim.fail_after").timeout(seconds, fail=True, shield=shield)

    def move_on_at(self, t: float, shield: bool = False) -> Any:
        """A cancel scope that gives up at sim time ``t``."""
        return self._runtime("sim.move_on_at").timeout(t, fail=False, shield=shield, absolute=True)

    def fail_at(self, t: float, shield: bool = False) -> Any:
        """Like :meth:`move_on_at` but raises TimeoutError at the deadline."""
        return self._runtime("sim.fail_at").timeout(t, fail=True, shield=shield, absolute=True)

    async def wait_until(self, predicate: Callable[[], bool]) -> None:
        """Wait until ``predicate()`` is true, checked after every step."""
        await self._runtime("sim.wait_until").wait_until(predicate)

    def task_group(self) -> Any:
        """A task group whose children are missions: ``async with sim.task_group() as tg``."""
        return self._runtime("sim.task_group").task_group()

    async def gather(self, *missions: Any) -> list[Any]:
        """Run missions (async callables or coroutines) concurrently; results in order."""
        return await self._runtime("sim.gather").gather(*missions)

    async def race(self, *missions: Any) -> tuple[int, Any]:
        """Run missions concurrently; return (index, result) of the first to finish.

        The losers are cancelled, and so are the actions they were waiting on.
        """
        return await self._runtime("sim.race").race(*missions)

    def mission_rng(self) -> Any:
        """A numpy Generator for the calling mission, derived from the seed and its spawn key."""
        return self._runtime("sim.mission_rng").mission_rng()


class SimEventBus(EventBus):
    """The simulation's event bus, which missions can also ``await`` events on."""

    __slots__ = ("_owner",)

    def __init__(self, owner: SimMissionApi, on_error: str = "raise") -> None:
        super().__init__(on_error)
        self._owner = owner

    async def wait(self, name: str, where: Callable[..., bool] | None = None) -> dict[str, Any]:
        """Wait for the next ``name`` event whose payload ``where(**payload)`` accepts.

        Returns:
            The event's payload as a dict.
        """
        runtime = self._owner.mission_runtime
        if runtime is None:
            raise _no_runtime("sim.events.wait")
        return await runtime.wait_event(name, where)

    def stream(self, name: str, where: Callable[..., bool] | None = None) -> Any:
        """An async iterator over every ``name`` event from now on (``where`` filters)::

        async with sim.events.stream("collision_started") as collisions:
            async for payload in collisions:
                ...
        """
        runtime = self._owner.mission_runtime
        if runtime is None:
            raise _no_runtime("sim.events.stream")
        return runtime.event_stream(name, where)
