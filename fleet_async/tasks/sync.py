"""Sim-aware synchronisation between missions: Event, Resource / Lock and Store.

They behave like their anyio / SimPy counterparts but park missions the way every sim-time
await does, so waking follows the mission-key order and the run stays deterministic. A waiter
that is cancelled (a timeout, a lost race) leaves the queue without taking anything.

    charger = Resource(sim, capacity=2)
    async with charger.request(priority=0):
        await robot.charge(30.0)
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections import deque
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from typing import TYPE_CHECKING, Any, cast

from fleet_async.tasks.parking import Waiter

if TYPE_CHECKING:
    from fleet_async.core.missions import MultiRobotSimulationCore
    from fleet_async.tasks.runtime import Runtime

__all__ = ["Event", "EventStream", "Lock", "Resource", "Store"]


def _runtime(sim: MultiRobotSimulationCore, what: str) -> Runtime:
    runtime = sim.mission_runtime
    if runtime is None:
        raise RuntimeError(
            f"{what} needs a running mission: start missions with fleet_async.run(sim, main)"
        )
    return cast("Runtime", runtime)  # the only MissionRuntime there is


class Event:
    """A flag missions can wait for; ``set`` wakes every waiter (in mission-key order)."""

    def __init__(self, sim: MultiRobotSimulationCore) -> None:
        self._sim = sim
        self._set = False
        self._waiters: dict[int, Waiter] = {}

    def is_set(self) -> bool:
        """Whether the event has been set."""
        return self._set

    def set(self) -> None:
        """Set the flag and wake every waiting mission."""
        if self._set:
            return
        self._set = True
        waiters, self._waiters = list(self._waiters.values()), {}
        if waiters:  # only a running mission can have parked here
            runtime = _runtime(self._sim, "Event.set")
            for waiter in waiters:
                runtime.schedule_wake(waiter)

    async def wait(self) -> None:
        """Wait until the event is set (returns at once if it is)."""
        runtime = _runtime(self._sim, "Event.wait")
        mission = runtime.current("Event.wait")
        if self._set:
            return
        waiter = Waiter(mission, "sync")
        key = id(waiter)

        def undo(_: Waiter) -> None:
            self._waiters.pop(key, None)

        waiter.on_abort = undo
        self._waiters[key] = waiter
        await runtime.park(waiter)


class Resource:
    """``capacity`` slots handed out by priority (lower first), then request order.

    Use ``async with resource.request(priority=...)`` or ``await acquire`` / ``release``.
    """

    def __init__(self, sim: MultiRobotSimulationCore, capacity: int = 1) -> None:
        if isinstance(capacity, bool) or not isinstance(capacity, int) or capacity < 1:
            raise ValueError(f"Resource.capacity: expected an integer >= 1, got {capacity!r}")
        self._sim = sim
        self.capacity = capacity
        self.in_use = 0
        self._queue: list[tuple[float, int, Waiter]] = []
        self._seq = itertools.count()

    @property
    def queued(self) -> int:
        """Missions waiting for a slot."""
        return len(self._queue)

    async def acquire(self, priority: float = 0.0) -> None:
        """Take a slot, waiting for one if all are in use."""
        runtime = _runtime(self._sim, "Resource.acquire")
        mission = runtime.current("Resource.acquire")
        if self.in_use < self.capacity and not self._queue:
            self.in_use += 1
            return
        waiter = Waiter(mission, "sync")
        entry = (float(priority), next(self._seq), waiter)

        def undo(_: Waiter) -> None:
            if entry in self._queue:
                self._queue.remove(entry)
                heapq.heapify(self._queue)

        waiter.on_abort = undo
        heapq.heappush(self._queue, entry)
        await runtime.park(waiter)  # the slot was handed over by release()

    def release(self) -> None:
        """Give a slot back; the next waiter (by priority, then order) gets it.

        Raises:
            RuntimeError: if no slot is held.
        """
        if self.in_use <= 0:
            raise RuntimeError("Resource.release: no slot is held")
        if self._queue:
            _, _, waiter = heapq.heappop(self._queue)
            _runtime(self._sim, "Resource.release").schedule_wake(waiter)  # slot passes on
        else:
            self.in_use -= 1

    @asynccontextmanager
    async def request(self, priority: float = 0.0) -> AsyncIterator[Resource]:
        """``async with resource.request():`` holds a slot for the block."""
        await self.acquire(priority)
        try:
            yield self
        finally:
            self.release()


class Lock(Resource):
    """A Resource with one slot: ``async with lock.request():``."""

    def __init__(self, sim: MultiRobotSimulationCore) -> None:
        super().__init__(sim, capacity=1)


class Store:
    """A FIFO of items: ``await put(item)`` (waits while full), ``await get(filter)``."""

    def __init__(self, sim: MultiRobotSimulationCore, capacity: float = math.inf) -> None:
        if not capacity >= 1:
            raise ValueError(f"Store.capacity: expected a number >= 1, got {capacity!r}")
        self._sim = sim
        self.capacity = capacity
        self.items: deque[Any] = deque()
        self._getters: list[tuple[Waiter, Callable[[Any], bool] | None]] = []
        self._putters: deque[tuple[Waiter, Any]] = deque()

    async def put(self, item: Any) -> None:
        """Add ``item``, waiting while the store is full."""
        runtime = _runtime(self._sim, "Store.put")
        mission = runtime.current("Store.put")
        if len(self.items) < self.capacity:
            self.items.append(item)
            self._serve(runtime)
            return
        waiter = Waiter(mission, "sync")
        entry = (waiter, item)

        def undo(_: Waiter) -> None:
            if entry in self._putters:
                self._putters.remove(entry)

        waiter.on_abort = undo
        self._putters.append(entry)
        await runtime.park(waiter)

    async def get(self, filter: Callable[[Any], bool] | None = None) -> Any:
        """Take the oldest item (matching ``filter``), waiting until there is one."""
        runtime = _runtime(self._sim, "Store.get")
        mission = runtime.current("Store.get")
        item = self._take(filter)
        if item is not _NOTHING:
            self._admit_putters(runtime)
            return item
        waiter = Waiter(mission, "sync")
        getter = (waiter, filter)

        def undo(_: Waiter) -> None:
            if getter in self._getters:
                self._getters.remove(getter)

        waiter.on_abort = undo
        self._getters.append(getter)
        return await runtime.park(waiter)

    def _take(self, filter: Callable[[Any], bool] | None) -> Any:
        for i, item in enumerate(self.items):
            if filter is None or filter(item):
                del self.items[i]
                return item
        return _NOTHING

    def _serve(self, runtime: Runtime) -> None:
        """Hand items to waiting getters, oldest getter first."""
        for entry in list(self._getters):
            waiter, flt = entry
            item = self._take(flt)
            if item is _NOTHING:
                continue
            self._getters.remove(entry)
            runtime.schedule_wake(waiter, item)
        self._admit_putters(runtime)

    def _admit_putters(self, runtime: Runtime) -> None:
        admitted = False
        while self._putters and len(self.items) < self.capacity:
            waiter, item = self._putters.popleft()
            self.items.append(item)
            runtime.schedule_wake(waiter)
            admitted = True
        if admitted and self._getters:
            self._serve(runtime)


class EventStream:
    """``async for payload in sim.events.stream(name, where=...)``: every matching event, in
    order, from subscription until ``close()`` (or leaving an ``async with`` block)."""

    def __init__(
        self, sim: MultiRobotSimulationCore, name: str, where: Callable[..., bool] | None
    ) -> None:
        self._sim = sim
        self._name = name
        self._where = where
        self._buffer: deque[dict[str, Any]] = deque()
        self._waiter: Waiter | None = None
        self._closed = False
        sim.events.on(name, self._on_event, priority=1_000_000)

    def _on_event(self, **payload: Any) -> None:
        if self._where is not None and not self._where(**payload):
            return
        if self._waiter is not None and not self._waiter.done:
            waiter, self._waiter = self._waiter, None
            _runtime(self._sim, "EventStream").schedule_wake(waiter, dict(payload))
        else:
            self._buffer.append(dict(payload))

    def close(self) -> None:
        """Stop listening."""
        if not self._closed:
            self._closed = True
            self._sim.events.off(self._name, self._on_event)

    def __aiter__(self) -> EventStream:
        return self

    async def __anext__(self) -> dict[str, Any]:
        if self._buffer:
            return self._buffer.popleft()
        if self._closed:
            raise StopAsyncIteration
        runtime = _runtime(self._sim, "EventStream")
        waiter = Waiter(runtime.current("sim.events.stream"), "event")

        def undo(_: Waiter) -> None:
            self._waiter = None

        waiter.on_abort = undo
        self._waiter = waiter
        payload: dict[str, Any] = await runtime.park(waiter)
        return payload

    async def __aenter__(self) -> EventStream:
        return self

    async def __aexit__(self, *exc: object) -> None:
        self.close()


_NOTHING = object()
