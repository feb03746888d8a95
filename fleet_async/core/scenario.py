"""Building a whole simulation from a scenario mapping or YAML file (skeleton)."""

from __future__ import annotations

__all__ = ["ScenarioApi"]


class ScenarioApi:
    """``from_dict`` / ``from_yaml`` / ``spawn_robots_from_config`` for MultiRobotSimulationCore."""
