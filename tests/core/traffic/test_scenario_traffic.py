"""The scenario's ``traffic:`` section and the entities' ``safety_field`` key."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from fleet_async import MultiRobotSimulationCore

DATA = Path(__file__).resolve().parents[2] / "data" / "traffic"
HEADLESS = {
    "gui": False,
    "monitor": False,
    "target_rtf": 0.0,
    "timestep": 0.1,
    "enable_floor": False,
}
BOX = {"shape_type": "box", "half_extents": [0.2, 0.2, 0.2]}


def scenario(tmp_path, **sections):
    for name in ("loop.graph.yaml", "warehouse-small.map"):
        shutil.copy(DATA / name, tmp_path / name)
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump({"simulation": HEADLESS, **sections}, sort_keys=False))
    return path


def test_a_scenario_loads_maps_a_route_graph_and_robots_with_fields(tmp_path):
    path = scenario(
        tmp_path,
        traffic={
            "route_graph": "loop.graph.yaml",
            "maps": [{"path": "warehouse-small.map", "resolution": 0.5, "height": 0.5}],
            "deadlock_after": 4.0,
        },
        entities=[
            {
                "name": "r1",
                "visual_shape": BOX,
                "collision_shape": BOX,
                "controller": "omni",
                "pose": [10.0, 10.0, 0.2],
                "safety_field": {"protective_margin": 0.2},
            }
        ],
    )
    with MultiRobotSimulationCore.from_yaml(path) as sim:
        assert sorted(sim.route_graph.nodes) == ["A", "B", "C", "D"]
        assert len(sim.maps) == 1 and sim.maps[0].grid.resolution == 0.5
        assert sim.safety.deadlock_after == 4.0
        (robot,) = sim.agents
        assert sim.safety.params_of(robot).protective_margin == 0.2


@pytest.mark.parametrize(
    ("traffic", "message"),
    [
        ({"route_grph": "loop.graph.yaml"}, "route_grph"),
        ({"maps": "warehouse-small.map"}, "traffic.maps: expected a list"),
        ({"maps": [{"path": "warehouse-small.map", "colour": 1}]}, "colour"),
        ({"deadlock_after": -1}, "deadlock_after"),
        ({"route_graph": "missing.yaml"}, "missing.yaml"),
    ],
)
def test_bad_traffic_sections_name_the_key_and_the_file(tmp_path, traffic, message):
    path = scenario(tmp_path, traffic=traffic)
    with pytest.raises((ValueError, FileNotFoundError), match=message) as info:
        MultiRobotSimulationCore.from_yaml(path)
    assert "scenario.yaml" in str(info.value)


def test_a_bad_safety_field_key_names_the_entity(tmp_path):
    entity = {"visual_shape": BOX, "collision_shape": BOX, "safety_field": {"margin": 1}}
    path = scenario(tmp_path, entities=[entity])
    with pytest.raises(ValueError, match=r"margin") as info:
        MultiRobotSimulationCore.from_yaml(path)
    assert "scenario.yaml" in str(info.value)
