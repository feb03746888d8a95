"""Sim-aware task groups, and gather / race built on them."""

from __future__ import annotations

import inspect
from collections.abc import Awaitable, Callable
from types import TracebackType
from typing import TYPE_CHECKING, Any

import anyio

if TYPE_CHECKING:
    from fleet_async.tasks.runtime import Mission, Runtime

__all__ = ["SimTaskGroup", "gather", "race"]


def _as_callable(item: Any) -> tuple[Callable[..., Awaitable[Any]], str]:
    """Accept a coroutine function (called with no arguments) or a coroutine object."""
    if inspect.iscoroutine(item):
        coro = item

        async def await_it() -> Any:
            return await coro

        return await_it, getattr(coro, "__name__", "coroutine")
    if callable(item):
        return item, getattr(item, "__name__", "mission")
    raise TypeError(f"expected a coroutine or an async callable, got {item!r}")


class SimTaskGroup:
    """An anyio task group whose tasks are missions (they may await sim time).

    Each child gets a stable key from its parent's spawn sequence, which fixes the order in
    which simultaneous wakes are delivered. While the parent waits in ``__aexit__`` for its
    children it counts as parked; the last child to finish counts it runnable again.
    """

    def __init__(self, runtime: Runtime) -> None:
        self._runtime = runtime
        self._tg = anyio.create_task_group()
        self._parent: Mission | None = None
        self._live = 0
        self._parent_waiting = False

    @property
    def cancel_scope(self) -> anyio.CancelScope:
        """The group's anyio cancel scope (``tg.cancel_scope.cancel()`` cancels every child)."""
        return self._tg.cancel_scope

    async def __aenter__(self) -> SimTaskGroup:
        self._parent = self._runtime.current("sim.task_group")
        await self._tg.__aenter__()
        return self

    def start_soon(
        self, fn: Callable[..., Awaitable[Any]], *args: Any, name: str | None = None
    ) -> None:
        """Start ``fn(*args)`` as a child mission."""
        assert self._parent is not None, "use 'async with sim.task_group() as tg'"
        key = self._parent.child_key()
        label = name or f"{self._parent.name}/{getattr(fn, '__name__', 'mission')}#{key[-1]}"
        self._live += 1
        self._runtime.spawn(self._tg, fn, args, key, label, on_done=self._child_done)

    def _child_done(self) -> None:
        self._live -= 1
        if self._live == 0 and self._parent_waiting:
            self._parent_waiting = False
            self._runtime.count_wake()  # the parent resumes from __aexit__

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> bool | None:
        if self._live == 0:
            return await self._tg.__aexit__(exc_type, exc, tb)
        self._parent_waiting = True
        self._runtime.note_parked()
        try:
            return await self._tg.__aexit__(exc_type, exc, tb)
        finally:
            if self._parent_waiting:  # left without the last child counting us back in
                self._parent_waiting = False
                self._runtime.count_wake()


async def gather(runtime: Runtime, *items: Any) -> list[Any]:
    """Run missions concurrently and return their results in argument order."""
    results: list[Any] = [None] * len(items)

    async def slot(i: int, fn: Callable[..., Awaitable[Any]]) -> None:
        results[i] = await fn()

    async with SimTaskGroup(runtime) as tg:
        for i, item in enumerate(items):
            fn, name = _as_callable(item)
            tg.start_soon(slot, i, fn, name=None if name == "mission" else f"gather[{i}]:{name}")
    return results


async def race(runtime: Runtime, *items: Any) -> tuple[int, Any]:
    """Run missions concurrently; return (index, result) of the first to finish.

    The others are cancelled, and so are the actions they were waiting on.
    """
    if not items:
        raise ValueError("race: expected at least one contender")
    winner: list[tuple[int, Any]] = []

    async def contender(i: int, fn: Callable[..., Awaitable[Any]], tg: SimTaskGroup) -> None:
        result = await fn()
        if not winner:
            winner.append((i, result))
            tg.cancel_scope.cancel()

    async with SimTaskGroup(runtime) as tg:
        for i, item in enumerate(items):
            fn, name = _as_callable(item)
            tg.start_soon(contender, i, fn, tg, name=f"race[{i}]:{name}")
    if not winner:
        raise RuntimeError("race: every contender was cancelled")
    return winner[0]
