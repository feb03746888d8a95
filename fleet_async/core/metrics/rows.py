"""The rows ``sim.kpis()`` returns: one summary row per run, one row per robot.

Each definition is documented in ``docs/sweeps.md``; ``fleet-async sweep`` writes one
:class:`FleetKpis` row per run, in :meth:`FleetKpis.columns` order.
"""

from __future__ import annotations

import dataclasses
from typing import Any

__all__ = ["FleetKpis", "RobotKpis"]


@dataclasses.dataclass(frozen=True)
class FleetKpis:
    """The fleet's summary row for one run (see ``docs/sweeps.md`` for each definition).

    Totals are over every robot counted; means divide a total by ``robot_count``. Times are in sim
    seconds, distances in metres, battery figures in state-of-charge units (1.0 = one full
    battery); battery fields are None when no robot has a battery.
    """

    robot_count: int
    steps: int
    sim_time_s: float
    tasks_completed: int
    tasks_failed: int
    throughput_per_hour: float
    actions_completed: int
    actions_failed: int
    actions_cancelled: int
    distance_total_m: float
    distance_mean_m: float
    moving_time_total_s: float
    moving_time_mean_s: float
    waiting_time_total_s: float
    waiting_time_mean_s: float
    idle_time_total_s: float
    idle_time_mean_s: float
    collisions: int
    mission_errors: int
    battery_robots: int
    battery_used_total: float | None
    battery_used_mean: float | None
    battery_min_soc: float | None
    safety_stops: int = 0
    safety_stopped_time_total_s: float = 0.0
    deadlocks_suspected: int = 0

    @classmethod
    def columns(cls) -> list[str]:
        """Field names, in row order."""
        return [f.name for f in dataclasses.fields(cls)]

    def as_dict(self) -> dict[str, Any]:
        """The row as ``{column: value}`` in column order."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class RobotKpis:
    """One robot's figures over the collector's window (same units as :class:`FleetKpis`)."""

    robot: str
    object_id: int
    distance_m: float
    moving_time_s: float
    waiting_time_s: float
    idle_time_s: float
    actions_completed: int
    actions_failed: int
    actions_cancelled: int
    tasks_completed: int
    tasks_failed: int
    collisions: int
    battery_used: float | None
    battery_soc: float | None
    safety_stops: int = 0
    safety_stopped_time_s: float = 0.0

    @classmethod
    def columns(cls) -> list[str]:
        """Field names, in row order."""
        return [f.name for f in dataclasses.fields(cls)]

    def as_dict(self) -> dict[str, Any]:
        """The row as ``{column: value}`` in column order."""
        return dataclasses.asdict(self)
