"""One colour per link: the GUI and recordings show a URDF body alike."""

from __future__ import annotations

import logging
from pathlib import Path

import pybullet as p

from fleet_async import Agent, Pose

REPO = Path(__file__).resolve().parents[2]

TWO_COLOURS = """<?xml version="1.0"?>
<robot name="two_colours">
  <link name="chassis">
    <visual>
      <geometry><box size="0.6 0.4 0.2"/></geometry>
      <material name="blue"><color rgba="0.2 0.3 0.8 1"/></material>
    </visual>
    <visual>
      <origin xyz="-0.25 0 -0.1"/>
      <geometry><sphere radius="0.05"/></geometry>
      <material name="grey"><color rgba="0.6 0.6 0.6 1"/></material>
    </visual>
  </link>
</robot>
"""


def colours(sim, body):
    return [
        tuple(round(c, 3) for c in v[7])
        for v in p.getVisualShapeData(body, physicsClientId=sim.client)
    ]


def test_a_link_of_several_colours_takes_its_largest_visuals_colour(sim, tmp_path, caplog):
    urdf = tmp_path / "two_colours.urdf"
    urdf.write_text(TWO_COLOURS)
    with caplog.at_level(logging.WARNING, logger="fleet_async"):
        first = Agent.from_urdf(str(urdf), pose=Pose.from_xyz(0, 0, 0.2), sim_core=sim)
        second = Agent.from_urdf(str(urdf), pose=Pose.from_xyz(2, 0, 0.2), sim_core=sim)
    blue = (0.2, 0.3, 0.8, 1.0)
    assert colours(sim, first.body_id) == [blue, blue] == colours(sim, second.body_id)
    warnings = [r.getMessage() for r in caplog.records if "several colours" in r.getMessage()]
    assert len(warnings) == 1  # once per file
    assert str(urdf) in warnings[0] and "'chassis'" in warnings[0]


def test_sdf_scenery_takes_the_colour_covering_most_of_it(sim, caplog):
    world = "examples/worlds/warehouse.world"
    with caplog.at_level(logging.INFO, logger="fleet_async"):
        sim.load_world({"world_file": str(REPO / world)})
    racks = [o for o in sim.sim_objects if "shelf" in o.name]
    assert racks
    for rack in racks:  # blue frame, three brown boards: brown covers most of it
        assert set(colours(sim, rack.body_id)) == {(0.8, 0.6, 0.35, 1.0)}
    assert any("several colours" in r.getMessage() for r in caplog.records)


def test_bundled_robots_need_no_repainting(sim, caplog):
    with caplog.at_level(logging.WARNING, logger="fleet_async"):
        for model in ("mobile_robot", "mobile_manipulator", "arm_robot", "simple_cube"):
            Agent.from_urdf(model, pose=Pose.from_xyz(0, 0, 0.2), sim_core=sim)
    assert not [r for r in caplog.records if "several colours" in r.getMessage()]
