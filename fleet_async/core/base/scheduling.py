"""Calling things at a frequency measured in sim time.

A periodic entry with frequency ``f`` runs at sim times ``1/f, 2/f, 3/f, ...`` (the first call
one period after the start, never at t = 0), computed as multiples of the period so that no
float error accumulates. An entry added later (at sim time ``now``) first runs at the next
multiple after ``now``, and its first ``dt`` is the time since it was added. An entry with
frequency None runs on every call to :meth:`due`. When the step is coarser than the period an
entry runs once per step, with the elapsed time.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

__all__ = ["PeriodicSchedule"]

# Tolerance (s) when comparing sim times built from integer steps with period multiples.
_EPS = 1e-9


@dataclass
class _Entry:
    callback: Callable[..., Any]
    period: float | None
    count: int = 0  # number of periods already served
    last_time: float = 0.0


class PeriodicSchedule:
    """An ordered set of callbacks, each with its own frequency in Hz of sim time."""

    def __init__(self) -> None:
        self._entries: list[_Entry] = []

    def __len__(self) -> int:
        return len(self._entries)

    def __iter__(self) -> Iterator[Callable[..., Any]]:
        return (e.callback for e in self._entries)

    def add(
        self,
        callback: Callable[..., Any],
        frequency: float | None,
        owner: str = "register_callback",
        now: float = 0.0,
    ) -> None:
        """Add ``callback`` at ``frequency`` Hz (None: every step), at sim time ``now``.

        Raises:
            TypeError: if ``callback`` is not callable.
            ValueError: if ``frequency`` is not None and not a finite number > 0.
        """
        if not callable(callback):
            raise TypeError(f"{owner}: callback is not callable: {callback!r}")
        period = None
        if frequency is not None:
            if (
                isinstance(frequency, bool)
                or not isinstance(frequency, (int, float))
                or not (math.isfinite(frequency) and frequency > 0)
            ):
                raise ValueError(
                    f"{owner}: frequency must be None or a number > 0 (Hz), got {frequency!r}"
                )
            period = 1.0 / float(frequency)
        served = 0 if period is None else math.floor((now + _EPS) / period)
        self._entries.append(_Entry(callback, period, served, now))

    def remove(self, callback: Callable[..., Any]) -> bool:
        """Remove the first entry for ``callback``; return whether there was one."""
        for i, entry in enumerate(self._entries):
            if entry.callback == callback:
                del self._entries[i]
                return True
        return False

    def clear(self) -> None:
        """Remove every entry."""
        self._entries.clear()

    def get_state(self) -> list[tuple[int, float]]:
        """Each entry's progress (periods served, last call time), in order (checkpoints)."""
        return [(e.count, e.last_time) for e in self._entries]

    def set_state(self, state: list[tuple[int, float]]) -> None:
        """Restore :meth:`get_state`'s progress onto the same entries.

        Raises:
            ValueError: if the number of entries differs.
        """
        if len(state) != len(self._entries):
            raise ValueError(
                f"the checkpoint has {len(state)} scheduled callbacks here, this simulation "
                f"{len(self._entries)}"
            )
        for entry, (count, last_time) in zip(self._entries, state, strict=True):
            entry.count, entry.last_time = count, last_time

    def reset(self) -> None:
        """Restart every entry's schedule from sim time 0."""
        for entry in self._entries:
            entry.count = 0
            entry.last_time = 0.0

    def due(
        self, now: float, step_dt: float | None = None
    ) -> list[tuple[Callable[..., Any], float]]:
        """Return ``(callback, dt)`` for every entry due at ``now``, advancing their schedules.

        ``dt`` is the sim time since the entry last ran (its period, in the steady state); for
        every-step entries it is ``step_dt``.
        """
        out = []
        for entry in tuple(self._entries):
            if entry.period is None:
                out.append(
                    (entry.callback, step_dt if step_dt is not None else now - entry.last_time)
                )
                entry.last_time = now
            elif now + _EPS >= (entry.count + 1) * entry.period:
                out.append((entry.callback, now - entry.last_time))
                entry.count = math.floor((now + _EPS) / entry.period)
                entry.last_time = now
        return out

    def steps_until_due(self, step: int, timestep: float, limit: int) -> int:
        """How many steps from ``step`` on (at most ``limit``) run before an entry is due.

        Step ``j`` runs at sim time ``j * timestep``; an every-step entry is due at once. The
        test is the one :meth:`due` applies, so the answer is exact, not an estimate.
        """
        free = limit
        for entry in self._entries:
            if entry.period is None:
                return 0
            boundary = (entry.count + 1) * entry.period
            j = max(step, math.ceil((boundary - _EPS) / timestep) - 1)
            while j * timestep + _EPS < boundary:  # first step at or after the boundary
                j += 1
            free = min(free, j - step)
            if free <= 0:
                return 0
        return free
