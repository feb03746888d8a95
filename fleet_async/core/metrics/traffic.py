"""Traffic KPIs: safety stops, time stopped by safety fields, deadlocks suspected.

A small piece the KPI collector (``kpis.py``) reads: it takes the safety fields' counts when
the collector starts and reports what has been added since, until the collector stops (then
the figures freeze). Definitions (``docs/traffic.md``): a *stop* is one
``safety_stop_started``; *time stopped* counts the steps a robot stood held by its
protective field; a *deadlock* is one ``deadlock_suspected``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["TrafficCounts"]


class TrafficCounts:
    """The safety fields' counts over a KPI collector's window.

    Args:
        sim: The simulation (its ``safety``).
    """

    def __init__(self, sim: SimulationKernel) -> None:
        self._sim = sim
        self._base = sim.safety.stats()
        self._base_deadlocks = sim.safety.deadlocks_suspected
        self._final: tuple[dict[int, tuple[int, float]], int] | None = None

    def freeze(self) -> None:
        """Keep the counts as they are now (the collector stopped)."""
        if self._final is None:
            self._final = self._now()

    def _now(self) -> tuple[dict[int, tuple[int, float]], int]:
        if self._final is not None:
            return self._final
        safety = self._sim.safety
        return safety.stats(), safety.deadlocks_suspected

    def robot(self, object_id: int) -> tuple[int, float]:
        """(stops, time stopped in s) of one robot in the window."""
        stats, _ = self._now()
        stops, stopped = stats.get(object_id, (0, 0.0))
        base_stops, base_stopped = self._base.get(object_id, (0, 0.0))
        return stops - base_stops, max(stopped - base_stopped, 0.0)

    def deadlocks(self) -> int:
        """``deadlock_suspected`` events in the window."""
        return self._now()[1] - self._base_deadlocks
