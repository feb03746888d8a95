"""Parking a mission on the event loop's cheapest primitive, per backend.

A mission that awaits something in sim time *parks*: it suspends until the runtime wakes it
with a value or an exception. On asyncio that is a bare Future; on trio it is
``wait_task_rescheduled`` / ``reschedule``. Both keep anyio cancel scopes working: asyncio
throws CancelledError into the parked task, trio calls the abort function. Either way the
runtime's ``aborted`` hook runs (synchronously on trio, when the task resumes on asyncio) so
it can count the task as runnable again and undo what the wait had set up.

``park`` is a generator-based coroutine that suspends on the backend primitive itself: an
``await agent.move(...)`` goes through as few Python frames as possible on every wake, which
is most of the cost of a wake once the event loop's own work is done.
"""

from __future__ import annotations

import asyncio
import types
from collections.abc import Awaitable, Callable, Generator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fleet_async.tasks.runtime import Runtime

__all__ = ["AsyncioParker", "Parker", "TrioParker", "Waiter", "parker_for_backend"]


class Waiter:
    """One park: who waits, on what kind of thing, and how to undo it if cancelled."""

    __slots__ = ("done", "handle", "kind", "mission", "on_abort", "target")

    def __init__(
        self, mission: Any, kind: str, on_abort: Callable[[Waiter], None] | None = None
    ) -> None:
        self.mission = mission
        self.kind = kind  # "timer", "action", "condition", "event", "sync", "join", "driver"
        self.on_abort = on_abort
        self.done = False  # woken or aborted: exactly one of the two happens
        self.handle: Any = None
        self.target: Any = None  # what it waits on, for on_abort (an action, a timer bucket)


class Parker:
    """Backend-specific suspend / resume for one runtime."""

    one_at_a_time = False
    """Whether wakes must be delivered one task at a time to keep the order deterministic."""
    needs_recheck = True
    """Whether a zero runnable count must be confirmed after yielding to the loop."""

    def __init__(self, runtime: Runtime) -> None:
        self.runtime = runtime

    def current_task(self) -> Any:
        """The running task object (a cheap identity for mission lookup)."""
        raise NotImplementedError

    def park(self, waiter: Waiter) -> Awaitable[Any]:
        """Suspend the current mission until ``wake(waiter)``; return the value or raise the
        exception given to ``wake``. Counts the mission parked; cancellable by anyio scopes."""
        raise NotImplementedError

    def wait_driver(self, waiter: Waiter) -> Awaitable[Any]:
        """Suspend the driver (not a mission) until ``wake(waiter)``."""
        raise NotImplementedError

    def wake(self, waiter: Waiter, value: Any = None, error: BaseException | None = None) -> None:
        """Resume a parked waiter."""
        raise NotImplementedError


class AsyncioParker(Parker):
    """asyncio: a Future per park. The ready queue is FIFO, so waking in key order suffices."""

    def current_task(self) -> Any:
        return asyncio.current_task()

    @types.coroutine
    def park(self, waiter: Waiter) -> Generator[Any, Any, Any]:
        fut = waiter.handle = asyncio.get_running_loop().create_future()
        mission = waiter.mission
        mission.waiter = waiter
        runtime = self.runtime
        runtime.decrement()
        try:
            return (yield from fut)
        except asyncio.CancelledError:
            runtime.aborted(waiter)
            raise
        finally:
            mission.waiter = None

    @types.coroutine
    def wait_driver(self, waiter: Waiter) -> Generator[Any, Any, Any]:
        fut = waiter.handle = asyncio.get_running_loop().create_future()
        try:
            return (yield from fut)
        finally:
            waiter.done = True

    def wake(self, waiter: Waiter, value: Any = None, error: BaseException | None = None) -> None:
        fut = waiter.handle
        if fut.done():
            return
        if error is not None:
            fut.set_exception(error)
        else:
            fut.set_result(value)


class TrioParker(Parker):
    """trio: wait_task_rescheduled. trio shuffles each batch of runnable tasks on purpose, so
    wakes are delivered one task at a time in key order."""

    one_at_a_time = True
    # trio calls the abort function synchronously when a scope is cancelled, so the counter
    # is exact the moment it reaches zero.
    needs_recheck = False

    def __init__(self, runtime: Runtime) -> None:
        super().__init__(runtime)
        import outcome  # ships with trio
        import trio  # only when running on trio

        self._lowlevel = trio.lowlevel
        self._value = outcome.Value
        self._error = outcome.Error

    def current_task(self) -> Any:
        return self._lowlevel.current_task()

    @types.coroutine
    def park(self, waiter: Waiter) -> Generator[Any, Any, Any]:
        lowlevel = self._lowlevel
        runtime = self.runtime
        waiter.handle = lowlevel.current_task()
        mission = waiter.mission
        mission.waiter = waiter

        def abort(_raise_cancel: Any) -> Any:
            runtime.aborted(waiter)
            return lowlevel.Abort.SUCCEEDED

        runtime.decrement()
        try:
            return (yield from lowlevel.wait_task_rescheduled(abort))
        finally:
            mission.waiter = None

    @types.coroutine
    def wait_driver(self, waiter: Waiter) -> Generator[Any, Any, Any]:
        lowlevel = self._lowlevel
        waiter.handle = lowlevel.current_task()

        def abort(_raise_cancel: Any) -> Any:
            waiter.done = True
            return lowlevel.Abort.SUCCEEDED

        return (yield from lowlevel.wait_task_rescheduled(abort))

    def wake(self, waiter: Waiter, value: Any = None, error: BaseException | None = None) -> None:
        result = self._error(error) if error is not None else self._value(value)
        self._lowlevel.reschedule(waiter.handle, result)


def parker_for_backend(name: str, runtime: Runtime) -> Parker:
    """The parker for anyio backend ``name`` ("asyncio" or "trio")."""
    if name == "asyncio":
        return AsyncioParker(runtime)
    if name == "trio":
        return TrioParker(runtime)
    raise ValueError(f"unsupported anyio backend {name!r}; expected 'asyncio' or 'trio'")
