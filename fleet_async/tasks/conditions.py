"""Waiting for any or all of several events: ``sim.any_of`` / ``sim.all_of``, ``a | b``,
``a & b``.

The condition's value is a dict from each event that had been processed when the condition
was, to its value, in the order the events were given (nested conditions flattened): so
``if request in await (request | sim.timeout(5)):`` tells whether the request was granted. A
failed event fails the condition with its exception.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from fleet_async.tasks.kernel import PENDING, Kernel, SimEvent

__all__ = ["AllOf", "AnyOf", "Condition"]


class Condition(SimEvent):
    """Triggers once ``evaluate(events, count)`` holds (``count``: events processed so far).

    Raises:
        ValueError: if an event belongs to another run.
    """

    __slots__ = ("_count", "_evaluate", "_events")

    def __init__(
        self,
        kernel: Kernel,
        evaluate: Callable[[tuple[SimEvent, ...], int], bool],
        events: Iterable[SimEvent],
    ) -> None:
        super().__init__(kernel)
        self._evaluate = evaluate
        self._events = tuple(events)
        self._count = 0
        for event in self._events:
            if not isinstance(event, SimEvent):
                raise TypeError(f"any_of / all_of take sim events, got {event!r}")
            if event.kernel is not kernel and not event.rebind(kernel):
                raise ValueError(f"{event!r} belongs to another run")
        if not self._events:
            self.succeed({})
            return
        for event in self._events:
            if event.callbacks is None:
                self._check(event)
            else:
                event.callbacks.append(self._check)
        self.callbacks.append(self._build_value)  # type: ignore[union-attr]  # fresh event

    def abandon(self, mission: Any, cancelled: bool = True) -> None:
        """Its waiting mission was cancelled or interrupted: if nobody else waits on the
        condition, stop watching its events and let each give up what its wait set up (a
        cancellation withdraws a request, an interrupt leaves it queued; an action is
        cancelled), as if the mission had awaited it alone."""
        if self.callbacks is None or len(self.callbacks) > 1:  # beyond _build_value
            return
        self.detach_checks()
        for event in self._events:
            if event.abandon is not None:
                event.abandon(mission, cancelled)

    def _check(self, event: SimEvent) -> None:
        if self.raw_value is not PENDING:
            return
        self._count += 1
        if not event.ok:
            self.fail(event.raw_value)
        elif self._evaluate(self._events, self._count):
            self.succeed()

    def _build_value(self, _: SimEvent) -> None:
        self.detach_checks()
        if self.ok:
            value: dict[SimEvent, Any] = {}
            self.collect_values(value)
            self.raw_value = value

    def collect_values(self, into: dict[SimEvent, Any]) -> None:
        for event in self._events:
            if isinstance(event, Condition):
                event.collect_values(into)
            elif event.callbacks is None:
                into[event] = event.raw_value

    def detach_checks(self) -> None:
        for event in self._events:
            callbacks = event.callbacks
            if callbacks and self._check in callbacks:
                callbacks.remove(self._check)
            if isinstance(event, Condition):
                event.detach_checks()


def _all(events: tuple[SimEvent, ...], count: int) -> bool:
    return len(events) == count


def _any(events: tuple[SimEvent, ...], count: int) -> bool:
    return count > 0 or not events


class AllOf(Condition):
    """Triggers when every event has been processed."""

    __slots__ = ()

    def __init__(self, kernel: Kernel, events: Iterable[SimEvent]) -> None:
        super().__init__(kernel, _all, events)


class AnyOf(Condition):
    """Triggers when the first event has been processed."""

    __slots__ = ()

    def __init__(self, kernel: Kernel, events: Iterable[SimEvent]) -> None:
        super().__init__(kernel, _any, events)
