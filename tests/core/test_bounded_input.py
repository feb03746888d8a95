"""Input whose size cannot fit is refused at once, naming it; error messages stay short
whatever the size of the value they show (issue 27)."""

from __future__ import annotations

import numpy as np
import pytest

from fleet_async import (
    AgentManager,
    AgentSpawnParams,
    GridSpawnParams,
    MultiRobotSimulationCore,
    SimulationParams,
)

HEADLESS = "simulation: {gui: false, monitor: false, target_rtf: 0, enable_floor: false}\n"


def _grid_scenario(tmp_path, count, share=None):
    simulation = HEADLESS
    if share is not None:
        simulation = HEADLESS.replace("}", f", memory_share: {share}}}")
    path = tmp_path / "fleet.yaml"
    path.write_text(
        simulation + "entities:\n"
        "  - {name: bot, type: agent, urdf_path: mobile_robot,\n"
        f"     grid: {{count: {count}, spacing: [1.0, 1.0]}}}}\n"
    )
    return path


def test_a_grid_that_cannot_fit_in_memory_is_refused_before_anything_is_built(tmp_path):
    path = _grid_scenario(tmp_path, 10_000_000)
    with pytest.raises(ValueError, match="bodies need at least") as info:
        MultiRobotSimulationCore.from_yaml(path)
    message = str(info.value)
    assert message.startswith(f"{path}: entities[0].grid: 10,000,000 bodies need at least")
    assert "GiB" in message and "memory_share" in message


def test_memory_share_sets_the_limit(tmp_path):
    with pytest.raises(ValueError, match=r"entities\[0\]\.grid: 4 bodies need"):
        MultiRobotSimulationCore.from_yaml(_grid_scenario(tmp_path, 4, share="1.0e-9"))
    with MultiRobotSimulationCore.from_yaml(_grid_scenario(tmp_path, 4, share=0.5)) as sim:
        assert len(sim.sim_objects) == 4
    with pytest.raises(ValueError, match=r"SimulationParams\.memory_share: .*got 0"):
        SimulationParams(memory_share=0)


def test_a_python_grid_spawn_that_cannot_fit_is_refused(sim):
    manager = AgentManager(sim_core=sim)
    grid = GridSpawnParams.from_count(10_000_000, spacing=[1.0, 1.0])
    with pytest.raises(ValueError, match=r"10,000,000 bodies need at least .* GiB"):
        manager.spawn_agents_grid(10_000_000, grid, AgentSpawnParams(urdf_path="mobile_robot"))
    assert sim.sim_objects == []


def test_cell_positions_cost_what_is_asked_not_the_grid_size():
    small = GridSpawnParams(0, 3, 0, 2, spacing=[1.0, 2.0, 0.5], offset=[1, 1, 0], z_max=1)
    every = small.cell_positions()
    assert every.shape == (24, 3)
    assert every[5].tolist() == [2.0, 3.0, 0.0] and every[23].tolist() == [4.0, 5.0, 0.5]
    assert np.array_equal(small.cell_positions(np.array([23, 5])), every[[23, 5]])
    huge = GridSpawnParams(0, 10**7, 0, 10**7, spacing=[1.0, 1.0], offset=[0.0, 0.0])  # 10^14 cells
    assert huge.cell_positions(np.arange(3)).tolist() == [[0, 0, 0], [1, 0, 0], [2, 0, 0]]


def test_a_yaml_alias_bomb_in_an_error_message_is_cut_short(tmp_path):
    nested = "[m, m, m, m, m, m, m, m, m, m]"
    for level in "abcdefghi":  # ten levels of ten: 10^10 leaves once expanded
        nested = f"&{level} [{nested}" + f", *{level}" * 9 + "]"
    path = tmp_path / "bomb.yaml"
    path.write_text(
        HEADLESS + "entities:\n  - name: r1\n    urdf_path: mobile_robot\n"
        f"    pose: [0, 0, 0.1]\n    actions: {nested}\n"
    )
    with pytest.raises(ValueError, match=r"actions\[0\]: expected a mapping, got \[\[") as info:
        MultiRobotSimulationCore.from_yaml(path)
    assert len(str(info.value)) < 600
