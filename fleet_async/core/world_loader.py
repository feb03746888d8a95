"""Loading world geometry: SDF files, mesh directories, Gazebo .world files (skeleton)."""

from __future__ import annotations

__all__ = ["WorldLoadingApi"]


class WorldLoadingApi:
    """``load_world`` for MultiRobotSimulationCore."""
