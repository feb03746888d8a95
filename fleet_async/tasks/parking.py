"""Parking a mission on the event loop's cheapest primitive, per backend.

A mission that awaits something in sim time *parks*: it suspends until the runtime wakes it
with a value or an exception. On asyncio that is a bare Future; on trio it is
``wait_task_rescheduled`` / ``reschedule``. Both keep anyio cancel scopes working: asyncio
cancels the task's await of the future, trio calls the abort function. Either way the
waiter's ``on_abort`` hook runs (synchronously on trio, when the task resumes on asyncio) so
the runtime can count the task as runnable again and undo what the wait had set up.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

__all__ = ["AsyncioParker", "Parker", "TrioParker", "Waiter", "parker_for_backend"]


class Waiter:
    """One park: who waits, on what kind of thing, and how to undo it if cancelled."""

    __slots__ = ("bucket", "done", "handle", "handle_target", "kind", "mission", "on_abort")

    def __init__(self, mission: Any, kind: str, on_abort: Callable[[], None] | None = None) -> None:
        self.mission = mission
        self.kind = kind  # "timer", "action", "condition", "event", "sync", "join", "driver"
        self.on_abort = on_abort
        self.done = False  # woken or aborted: exactly one of the two happens
        self.handle: Any = None
        self.bucket: list[Waiter] | None = None  # the timer bucket holding it, if any
        self.handle_target: Any = None  # what an "action" wait waits on


class Parker:
    """Backend-specific suspend / resume."""

    one_at_a_time = False
    """Whether wakes must be delivered one task at a time to keep the order deterministic."""
    needs_recheck = True
    """Whether a zero runnable count must be confirmed after yielding to the loop."""

    def current_task(self) -> Any:
        """The running task object (a cheap identity for mission lookup)."""
        raise NotImplementedError

    def prepare(self, waiter: Waiter) -> None:
        """Create the backend handle for ``waiter`` (in the waiting task)."""
        raise NotImplementedError

    async def wait(self, waiter: Waiter, on_cancel: Callable[[Waiter], None]) -> Any:
        """Suspend until woken; return the value or raise the exception given to ``wake``."""
        raise NotImplementedError

    def wake(self, waiter: Waiter, value: Any = None, error: BaseException | None = None) -> None:
        """Resume a parked waiter."""
        raise NotImplementedError


class AsyncioParker(Parker):
    """asyncio: a Future per park. The ready queue is FIFO, so waking in key order suffices."""

    def current_task(self) -> Any:
        return asyncio.current_task()

    def prepare(self, waiter: Waiter) -> None:
        waiter.handle = asyncio.get_running_loop().create_future()

    async def wait(self, waiter: Waiter, on_cancel: Callable[[Waiter], None]) -> Any:
        try:
            return await waiter.handle
        except asyncio.CancelledError:
            on_cancel(waiter)
            raise

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

    def __init__(self) -> None:
        import trio  # only when running on trio

        self._trio = trio

    def current_task(self) -> Any:
        return self._trio.lowlevel.current_task()

    def prepare(self, waiter: Waiter) -> None:
        waiter.handle = self._trio.lowlevel.current_task()

    async def wait(self, waiter: Waiter, on_cancel: Callable[[Waiter], None]) -> Any:
        lowlevel = self._trio.lowlevel

        def abort(_raise_cancel: Any) -> Any:
            on_cancel(waiter)
            return lowlevel.Abort.SUCCEEDED

        return await lowlevel.wait_task_rescheduled(abort)

    def wake(self, waiter: Waiter, value: Any = None, error: BaseException | None = None) -> None:
        import outcome  # ships with trio

        result = outcome.Error(error) if error is not None else outcome.Value(value)
        self._trio.lowlevel.reschedule(waiter.handle, result)


def parker_for_backend(name: str) -> Parker:
    """The parker for anyio backend ``name`` ("asyncio" or "trio")."""
    if name == "asyncio":
        return AsyncioParker()
    if name == "trio":
        return TrioParker()
    raise ValueError(f"unsupported anyio backend {name!r}; expected 'asyncio' or 'trio'")
