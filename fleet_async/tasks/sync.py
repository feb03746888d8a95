"""Sim-aware Event and EventStream.

``Event(sim)`` is a one-shot event in sim time (anyio's ``set`` / ``is_set`` / ``wait``, and
SimPy's ``succeed(value)`` / ``fail(exc)`` / ``value``): awaiting it returns its value. Setting it
schedules it at the current step; its waiters resume, in the order they started waiting, when
the kernel processes it. It may be created before the run and set from outside the missions
(a callback, another task of the host loop).

``sim.events.stream(name)`` is an async iterator over the simulation's bus events.
"""

from __future__ import annotations

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

    __slots__ = ("_sim",)

    def __init__(self, sim: Any) -> None:
        runtime = sim.mission_runtime
        super().__init__(runtime.kernel if runtime is not None else _NO_KERNEL)
        self._sim = sim

    def _bind(self, what: str) -> Kernel:
        kernel = kernel_of(self._sim, what)
        if self.kernel is not kernel:  # made before this run (or in an earlier one)
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
        if self._sim.mission_runtime is None:  # no run: nobody can be waiting
            if self.raw_value is not PENDING:
                raise RuntimeError(f"{self!r} has already been triggered")
            self.ok, self.raw_value, self.callbacks = True, value, None
            return self
        self._bind("Event.succeed")
        super().succeed(value)
        return self

    def fail(self, exception: BaseException) -> Event:
        """Trigger it with an exception, which its waiters raise."""
        self._bind("Event.fail")
        super().fail(exception)
        return self

    def wait(self) -> Event:
        """``await event.wait()``: wait until it is set (returns its value)."""
        return self

    def __await__(self) -> Generator[Any, Any, Any]:
        kernel = self._bind("Event.wait")
        if kernel.current is None:
            raise kernel.outside_error("Event.wait")
        return (yield self)


class _NoKernel(Kernel):
    """Stands in for the kernel of an Event made outside a run."""


_NO_KERNEL = _NoKernel()


class EventStream:
    """``async for payload in sim.events.stream(name, where=...)``: every matching bus event,
    in order, from subscription until ``close()`` (or leaving an ``async with`` block)."""

    def __init__(self, runtime: Any, name: str, where: Callable[..., bool] | None) -> None:
        self._runtime = runtime
        self._name = name
        self._where = where
        self._buffer: deque[dict[str, Any]] = deque()
        self._waiter: SimEvent | None = None
        self._closed = False
        runtime.sim.events.on(name, self._on_event, priority=1_000_000)

    def _on_event(self, **payload: Any) -> None:
        if self._where is not None and not self._where(**payload):
            return
        waiter = self._waiter
        if waiter is not None:
            self._waiter = None
            self._runtime.streams_waiting -= 1
            waiter.succeed(dict(payload))
        else:
            self._buffer.append(dict(payload))

    def close(self) -> None:
        """Stop listening."""
        if not self._closed:
            self._closed = True
            self._runtime.sim.events.off(self._name, self._on_event)

    def __aiter__(self) -> EventStream:
        return self

    async def __anext__(self) -> dict[str, Any]:
        if self._buffer:
            return self._buffer.popleft()
        if self._closed:
            raise StopAsyncIteration
        waiter = _StreamWait(self._runtime.kernel, self)
        self._waiter = waiter
        self._runtime.streams_waiting += 1
        payload: dict[str, Any] = await waiter
        return payload

    def abandon(self, waiter: SimEvent) -> None:
        """Its waiting mission gave up (cancelled or interrupted)."""
        if self._waiter is waiter:
            self._waiter = None
            self._runtime.streams_waiting -= 1

    async def __aenter__(self) -> EventStream:
        return self

    async def __aexit__(self, *exc: object) -> None:
        self.close()


class _StreamWait(SimEvent):
    __slots__ = ("_stream",)

    def __init__(self, kernel: Kernel, stream: EventStream) -> None:
        super().__init__(kernel)
        self._stream = stream

    def abandon(self, mission: Any) -> None:
        self._stream.abandon(self)
