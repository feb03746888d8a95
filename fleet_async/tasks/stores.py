"""Stores of items in sim time: Store (FIFO, optionally filtered gets), FilterStore,
PriorityStore.

    parts = Store(sim, capacity=10)
    await parts.put("bolt")                          # waits while the store is full
    item = await parts.get(lambda p: p != "nut")     # waits for a matching item

A put is served at once if there is room, and waiting gets are served when the kernel processes
the put (SimPy's order); a get that can be served at once still yields once.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable
from typing import Any, NamedTuple

from fleet_async.tasks.queueing import GetRequest, PutRequest, Queueing

__all__ = ["FilterStore", "PriorityItem", "PriorityStore", "Store", "StoreGet", "StorePut"]


class StorePut(PutRequest):
    """Putting ``item`` into a store (an event that succeeds once there is room)."""

    __slots__ = ("item",)

    def __init__(self, store: Store, item: Any, give_back: bool = False) -> None:
        self.item = item
        super().__init__(store, "Store.put", give_back)


class StoreGet(GetRequest):
    """Taking an item (matching ``filter``) out of a store; the event's value is the item."""

    __slots__ = ("filter",)

    def __init__(self, store: Store, filter: Callable[[Any], bool] | None) -> None:
        self.filter = filter
        super().__init__(store, "Store.get")


class Store(Queueing):
    """Items in arrival order, up to ``capacity``; gets take the oldest item that matches.

    Raises:
        ValueError: if ``capacity`` is not a number >= 1.
    """

    def __init__(self, sim: Any, capacity: float = math.inf) -> None:
        if not capacity >= 1:
            raise ValueError(f"Store.capacity: expected a number >= 1, got {capacity!r}")
        super().__init__(sim)
        self.capacity = capacity
        self.items: list[Any] = []

    def put(self, item: Any) -> StorePut:
        """Add ``item`` (an event that succeeds once there is room)."""
        return StorePut(self, item)

    def get(self, filter: Callable[[Any], bool] | None = None) -> StoreGet:
        """Take the oldest item (matching ``filter``); the event's value is the item."""
        return StoreGet(self, filter)

    def try_put(self, request: StorePut) -> bool:
        """Add the item if there is room (one put per turn, as SimPy)."""
        if len(self.items) < self.capacity:
            self._add(request.item)
            request.succeed()
        return False

    def try_get(self, request: StoreGet) -> bool:
        """Hand the oldest matching item to ``request``. After a plain get, stop (one get per
        turn, SimPy's Store); after a filtered one, go on (a filtered get that cannot be
        served does not block the ones behind it, SimPy's FilterStore)."""
        for i, item in enumerate(self.items):
            if request.filter is None or request.filter(item):
                del self.items[i]
                request.succeed(item)
                break
        return request.filter is not None

    def restore(self, request: StoreGet) -> None:  # type: ignore[override]  # its own gets
        """Give back the item a cancelled get took: a put first in line, served before any
        other (it waits for room if others filled the store meanwhile: never over capacity)."""
        StorePut(self, request.raw_value, give_back=True)

    def _add(self, item: Any) -> None:
        self.items.append(item)


class FilterStore(Store):
    """A Store whose every get may take a filter, and whose gets never block each other
    (SimPy's FilterStore: all waiting gets are tried on every turn)."""

    def try_get(self, request: StoreGet) -> bool:
        """Hand the oldest matching item to ``request``; go on with the next get."""
        super().try_get(request)
        return True


class PriorityItem(NamedTuple):
    """An item with a priority for a PriorityStore; ordered by priority only."""

    priority: Any
    item: Any

    def __lt__(self, other: object) -> bool:
        if not isinstance(other, PriorityItem):
            return NotImplemented
        return bool(self.priority < other.priority)


class PriorityStore(Store):
    """A store whose gets take the smallest item first (use PriorityItem to rank items)."""

    def get(self, filter: Callable[[Any], bool] | None = None) -> StoreGet:
        """Take the smallest item.

        Raises:
            ValueError: if a filter is given (a priority store serves in priority order).
        """
        if filter is not None:
            raise ValueError("PriorityStore.get takes no filter: it serves the smallest item")
        return StoreGet(self, None)

    def try_get(self, request: StoreGet) -> bool:
        """Hand the smallest item to ``request``."""
        if self.items:
            request.succeed(heapq.heappop(self.items))
        return False

    def _add(self, item: Any) -> None:
        heapq.heappush(self.items, item)
