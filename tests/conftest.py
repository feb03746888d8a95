"""Shared fixtures: a headless simulation with a fixed timestep and seed."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from fleet_async import MultiRobotSimulationCore, SimulationParams


def headless_params(**overrides: object) -> SimulationParams:
    """Params for tests: DIRECT, no pacing, no monitor, dt = 0.1 s, seed 0."""
    values: dict[str, object] = {
        "gui": False,
        "monitor": False,
        "target_rtf": 0.0,
        "timestep": 0.1,
        "seed": 0,
    }
    values.update(overrides)
    return SimulationParams(**values)  # type: ignore[arg-type]


@pytest.fixture
def sim() -> Iterator[MultiRobotSimulationCore]:
    """A fresh headless simulation, disconnected afterwards."""
    core = MultiRobotSimulationCore(headless_params())
    yield core
    core.close()
