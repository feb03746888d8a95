"""Sim-aware Event and EventStream.

``Event(sim)`` is a one-shot event in sim time (anyio's ``set`` / ``is_set`` / ``wait``, and
SimPy's ``succeed(value)`` / ``fail(exc)`` / ``value``): awaiting it returns its value. Setting it
schedules it at the current step; its waiters resume, in the order they started waiting, when
the kernel processes it. It may be created before the run and set from outside the missions
(a callback, another task of the host loop). A failed Event that nobody waits on fails the run
when it is processed, naming where it was made, unless ``event.defused = True``.

``sim.events.stream(name)`` is an async iterator over the simulation's bus events.
"""

from __future__ import annotations

import inspect
import os
from collections import deque
from collections.abc import Callable, Generator
from typing import Any

from fleet_async.tasks.kernel import PENDING, Kernel, SimEvent, kernel_of

__all__ = ["Event", "EventStream"]


class Event(SimEvent):
    """A one-shot event missions can wait for.

    Args:
        sim: The simulation whose runs the event belongs to.
    """

    __slots__ = ("_sim", "created_at")

    def __init__(self, sim: Any) -> None:
        super().__init__(kernel_of(sim, "Event"))
        self._sim = sim
        self.created_at = _caller()
        """Where it was made (``file:line``), for the message of an unhandled failure."""

    def _bind(self, what: str) -> Kernel:
        kernel = kernel_of(self._sim, what)
        if self.kernel is not kernel:  # made for a runtime that was ended since
            self.kernel = kernel
            # Set back then, it counts as processed; if not, whoever waited then is gone.
            self.callbacks = None if self.raw_value is not PENDING else []
        return kernel

    def is_set(self) -> bool:
        """Whether it has been set (succeeded)."""
        return self.raw_value is not PENDING and self.ok

    def set(self, value: Any = None) -> None:
        """Set it (again: no effect); its waiters resume at the current step, in order."""
        if self.raw_value is not PENDING:
            return
        self.succeed(value)

    def succeed(self, value: Any = None) -> Event:
        """Trigger it with ``value``.

        Raises:
            RuntimeError: if it was triggered already.
        """
        self._bind("Event.succeed")
        super().succeed(value)
        return self

    def fail(self, exception: BaseException) -> Event:
        """Trigger it with an exception, which its waiters raise."""
        self._bind("Event.fail")
        super().fail(exception)
        return self

    def rebind(self, kernel: Kernel) -> bool:
        """An Event made for an ended runtime joins this one when a condition takes it."""
        runtime = self._sim.mission_runtime
        if runtime is not None and runtime.kernel is kernel:
            self._bind("sim.any_of / sim.all_of")
        return self.kernel is kernel

    def __or__(self, other: SimEvent) -> SimEvent:
        self._bind("Event | ...")
        return super().__or__(other)

    def __and__(self, other: SimEvent) -> SimEvent:
        self._bind("Event & ...")
        return super().__and__(other)

    def wait(self) -> Event:
        """``await event.wait()``: wait until it is set (returns its value)."""
        return self

    def __await__(self) -> Generator[Any, Any, Any]:
        kernel = self._bind("Event.wait")
        if kernel.current is None:
            raise kernel.outside_error("Event.wait")
        return (yield self)


def _caller() -> str:
    """``file:line`` of the first frame outside the mission layer (who made the event)."""
    frame = inspect.currentframe()
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE):
        frame = frame.f_back
    if frame is None:
        return "an unknown place"
    return f"{frame.f_code.co_filename}:{frame.f_lineno}"


_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep


class EventStream:
    """``async for payload in sim.events.stream(name, where=...)``: every matching bus event,
    in order, from subscription until ``close()`` (leaving an ``async with`` block, or the end
    of the run). Several missions may read one stream: each item goes to one reader, the one
    that has waited longest."""

    def __init__(self, runtime: Any, name: str, where: Callable[..., bool] | None) -> None:
        self._runtime = runtime
        self._name = name
        self._where = where
        self._buffer: deque[dict[str, Any]] = deque()
        self._waiters: deque[_StreamWait] = deque()
        self._closed = False
        runtime.sim.events.on(name, self._on_event, priority=1_000_000)

    @property
    def waiting(self) -> bool:
        """Whether a mission waits for the next item."""
        return bool(self._waiters)

    def _on_event(self, **payload: Any) -> None:
        if self._where is not None and not self._where(**payload):
            return
        if self._waiters:
            self._waiters.popleft().succeed(dict(payload))
        else:
            self._buffer.append(dict(payload))

    def close(self) -> None:
        """Stop listening; missions waiting for an item end their ``async for``."""
        if self._closed:
            return
        self._closed = True
        self._runtime.sim.events.off(self._name, self._on_event)
        while self._waiters:
            self._waiters.popleft().succeed(_END)

    def __aiter__(self) -> EventStream:
        return self

    async def __anext__(self) -> dict[str, Any]:
        if self._buffer:
            return self._buffer.popleft()
        if self._closed:
            raise StopAsyncIteration
        waiter = _StreamWait(self._runtime.kernel, self)
        self._waiters.append(waiter)
        payload: Any = await waiter
        if payload is _END:
            raise StopAsyncIteration
        result: dict[str, Any] = payload
        return result

    def abandon(self, waiter: _StreamWait) -> None:
        """A waiting mission gave up (cancelled or interrupted)."""
        if waiter in self._waiters:
            self._waiters.remove(waiter)

    async def __aenter__(self) -> EventStream:
        return self

    async def __aexit__(self, *exc: object) -> None:
        self.close()


_END: Any = object()
"""What a closed stream hands its waiting readers."""


class _StreamWait(SimEvent):
    __slots__ = ("_stream",)

    def __init__(self, kernel: Kernel, stream: EventStream) -> None:
        super().__init__(kernel)
        self._stream = stream

    def abandon(self, mission: Any, cancelled: bool = True) -> None:
        self._stream.abandon(self)
