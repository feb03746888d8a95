"""Per-object callbacks in the order they fall due, not checked object by object each step.

Each object with callbacks sits in a heap under the first step at which one of its callbacks
is due (its own schedule's exact test, ``callback_steps_until_due``). A step pops the objects
due then and runs them in the order they first registered a callback (what a scan of every
object did), then files each under its next due step. A step where nothing is due costs one
comparison, so callbacks also tell idle-step skipping exactly how far it may go.

Being filed too early is harmless (the object's schedule runs only what is due), so changes
outside a step (a callback registered or removed, a schedule restored from a checkpoint) only
have to re-file the object; a clock that went back (``initialize_simulation``) re-files all.
"""

from __future__ import annotations

import heapq
from collections.abc import Mapping
from typing import Protocol

__all__ = ["CallbackQueue", "ScheduledObject"]

_FAR = 1 << 40  # steps: "not within any horizon"


class ScheduledObject(Protocol):
    """An object with per-object callbacks, as the queue sees it."""

    @property
    def object_id(self) -> int: ...

    def has_callbacks(self) -> bool: ...

    def execute_callbacks(self, current_time: float) -> None: ...

    def callback_steps_until_due(self, step: int, timestep: float, limit: int) -> int: ...


class CallbackQueue:
    """The objects with callbacks of one world, by due step."""

    def __init__(self) -> None:
        self._heap: list[tuple[int, int, int, int]] = []  # (due step, order, id, version)
        self._order: dict[int, int] = {}  # object id -> first-registration sequence
        self._version: dict[int, int] = {}
        self._refile: set[int] = set()  # ids to file again before the next look
        self._seq = 0
        self._next_step = 0  # the step the heap is filed for

    def changed(self, obj: ScheduledObject) -> None:
        """``obj`` gained or lost callbacks, or its schedule changed: file it again."""
        key = obj.object_id
        self._version[key] = self._version.get(key, 0) + 1
        if obj.has_callbacks():
            if key not in self._order:
                self._order[key] = self._seq
                self._seq += 1
            self._refile.add(key)
        else:
            self._order.pop(key, None)
            self._refile.discard(key)

    def clear(self) -> None:
        """Forget every object (the world is being reset)."""
        self._heap.clear()
        self._order.clear()
        self._version.clear()
        self._refile.clear()

    def run(self, objects: Mapping[int, ScheduledObject], step: int, now: float, dt: float) -> None:
        """Run the callbacks of every object due at step ``step`` (sim time ``now``)."""
        self._file(objects, step, dt)
        heap = self._heap
        if not heap or heap[0][0] > step:
            self._next_step = step + 1
            return
        due: list[tuple[int, int]] = []
        while heap and heap[0][0] <= step:
            _, order, key, version = heapq.heappop(heap)
            if self._version.get(key) == version and key in self._order:
                due.append((order, key))
        due.sort()
        for _, key in due:
            obj = objects.get(key)
            if obj is not None:
                obj.execute_callbacks(now)
                self._refile.add(key)
        self._next_step = step + 1
        self._file(objects, step + 1, dt)

    def steps_until_due(
        self, objects: Mapping[int, ScheduledObject], step: int, dt: float, limit: int
    ) -> int:
        """How many steps from ``step`` on (at most ``limit``) run before a callback is due."""
        self._file(objects, step, dt)
        heap = self._heap
        while heap:
            due, _, key, version = heap[0]
            if self._version.get(key) == version and key in self._order:
                return max(0, min(limit, due - step))
            heapq.heappop(heap)
        return limit

    def _file(self, objects: Mapping[int, ScheduledObject], step: int, dt: float) -> None:
        if step < self._next_step:  # the clock went back: every schedule restarted
            self._refile.update(self._order)
        self._next_step = step
        if not self._refile:
            return
        for key in sorted(self._refile):
            obj = objects.get(key)
            if obj is None or key not in self._order:
                continue
            version = self._version[key] = self._version.get(key, 0) + 1
            due = step + obj.callback_steps_until_due(step, dt, _FAR)
            heapq.heappush(self._heap, (due, self._order[key], key, version))
        self._refile.clear()
        if len(self._heap) > 4 * len(self._order) + 64:  # drop stale entries now and then
            self._heap = [e for e in self._heap if self._version.get(e[2]) == e[3]]
            heapq.heapify(self._heap)
