"""Geometry, configs, grids, collisions and callbacks as a pybullet_fleet script uses them
(issue 15): the seed's text where it speaks, else the incumbent's public behaviour."""

from __future__ import annotations

import math

import pytest

from fleet_async.action import JointAction
from fleet_async.agent import Agent, AgentSpawnParams
from fleet_async.agent_manager import AgentManager, GridSpawnParams
from fleet_async.core_simulation import MultiRobotSimulationCore
from fleet_async.geometry import Path, Pose
from fleet_async.sim_object import ShapeParams, SimObject
from fleet_async.tools import grid_to_world, world_to_grid
from fleet_async.types import ActionStatus, CollisionMode
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def test_pose_from_yaw():
    pose = Pose.from_yaw(1, 2, 0, math.pi / 2)
    assert pose.position.tolist() == [1.0, 2.0, 0.0]
    assert pose.orientation == pytest.approx([0, 0, math.sqrt(0.5), math.sqrt(0.5)])
    assert pose == Pose.from_euler(1, 2, 0, yaw=math.pi / 2)


def test_grid_conversions_are_always_3d():
    # tools.world_to_grid: "Convert world coordinates to grid indices (always 3D)".
    assert world_to_grid([1.2, 3.7], [1, 1]) == [1, 4, 0]
    assert grid_to_world([1, 4], [1, 1]) == [1.0, 4.0, 0.0]


def test_a_square_patrol_comes_back_to_its_start(sim):
    square = Path.create_square(center=[0, 0, 0.1], side_length=2.0)
    assert len(square) == 5 and square[-1].position.tolist() == square[0].position.tolist()
    assert len(Path.create_circle(center=[0, 0, 0], radius=1.0, num_points=8)) == 9


def test_patrol_takes_the_incumbents_wait_time_key(sim):
    robot = Agent.from_mesh(
        BOX,
        BOX,
        Pose.from_xyz(0, 0, 0.1),
        sim_core=sim,
        controller=[
            {"type": "omni"},
            {"type": "patrol", "waypoints": [[1, 0, 0.1], [0, 0, 0.1]], "wait_time": 1.0},
        ],
    )
    assert robot.controllers[-1].wait == 1.0
    xs = []
    for _ in range(40):
        sim.step_once()
        xs.append(robot.get_pose().x)
    first = xs.index(1.0)
    # It arrives, then really waits 1.0 s (10 steps) before leaving for the next waypoint.
    assert xs[first : first + 11] == [1.0] * 11 and xs[first + 11] < 1.0
    with pytest.raises(ValueError, match="wait_time"):
        Agent.from_mesh(
            BOX,
            BOX,
            Pose.from_xyz(0, 0, 0.1),
            sim_core=sim,
            controller=[
                {"type": "omni"},
                {"type": "patrol", "waypoints": [[1, 0, 0.1]], "wait": 1.0, "wait_time": 2.0},
            ],
        )


def test_grid_spawned_entities_are_numbered(sim):
    objs = sim.spawn_robots_from_config(
        [
            {
                "name": "picker",
                "urdf_path": "robots/simple_cube.urdf",
                "grid": {"count": 3, "spacing": [3.0, 3.0], "offset": [0, 0, 0.05]},
            },
            {
                "type": "sim_object",
                "name": "tote",
                "visual_shape": {"shape_type": "box", "half_extents": [0.1, 0.1, 0.1]},
                "grid": {"count": 2, "spacing": [1.0, 1.0], "offset": [0, 10, 0.1]},
            },
            {"urdf_path": "robots/simple_cube.urdf", "grid": {"count": 1, "spacing": [1, 1]}},
        ]
    )
    assert [o.name for o in objs] == ["picker_0", "picker_1", "picker_2", "tote_0", "tote_1", None]
    manager = AgentManager(sim_core=sim)
    params = AgentSpawnParams(visual_shape=BOX, name="bot")
    grid = {"count": 2, "spacing": [1.0, 1.0], "offset": [0, 20, 0.1]}
    bots = manager.spawn_agents_grid(2, GridSpawnParams.from_dict(grid), params)
    assert [b.name for b in bots] == ["bot", "bot"]  # direct manager calls keep the name
    named = manager.spawn_agents_grid(
        2, GridSpawnParams.from_dict({**grid, "offset": [0, 30, 0.1]}), params, name_prefix="b"
    )
    assert [b.name for b in named] == ["b_0", "b_1"]


def test_overlapping_static_objects_are_reported_when_static_collisions_are_on():
    # SimulationParams.ignore_static_collision; filter_aabb_pairs: "ignore_static - If True,
    # skip collision checks with static objects".
    for ignore, expected in ((True, 0), (False, 1)):
        with MultiRobotSimulationCore(headless_params(ignore_static_collision=ignore)) as sim:
            for x in (0.0, 0.3):
                SimObject.from_mesh(
                    BOX, BOX, Pose.from_xyz(x, 0, 1.0), sim_core=sim, collision_mode="static"
                )
            sim.step_once()
            sim.step_once()
            assert len(sim.get_active_collision_pairs()) == expected
            assert sim.collision_count == expected  # started once


def test_a_late_callback_first_dt_is_the_time_since_it_was_registered(sim):
    seen = []
    for _ in range(7):
        sim.step_once()
    sim.register_callback(lambda s, dt: seen.append((round(s.sim_time, 9), round(dt, 9))), 2.0)
    for _ in range(10):
        sim.step_once()
    assert seen == [(1.0, 0.3), (1.5, 0.5)]


def test_the_seeds_rail_arm_joint_tolerance_example(sim):
    # agent.joint_tolerance / JointAction examples: {"rail_joint": ..., "elbow_to_wrist": ...}
    arm = Agent.from_urdf(
        "rail_arm_robot.urdf",
        use_fixed_base=True,
        sim_core=sim,
        joint_tolerance={"rail_joint": 0.005, "elbow_to_wrist": 0.05},
    )
    action = JointAction(
        target_joint_positions={"rail_joint": 0.3, "elbow_to_wrist": -0.3},
        tolerance={"rail_joint": 0.005, "elbow_to_wrist": 0.05},
    )
    arm.add_action(action)
    for _ in range(30):
        sim.step_once()
    assert action.status is ActionStatus.COMPLETED
    assert arm.get_joint_state_by_name("rail_joint")[0] == pytest.approx(0.3)
    assert arm.collision_mode is CollisionMode.NORMAL_3D


def test_a_grid_that_is_too_small_is_the_error_reported_first():
    manager = AgentManager()  # no simulation, so no random generator either
    grid = GridSpawnParams(x_min=0, x_max=0, y_min=0, y_max=0, spacing=[1, 1, 0], offset=[0, 0, 0])
    with pytest.raises(ValueError, match="spawn_grid_counts: 2 objects do not fit"):
        manager.spawn_grid_counts(grid, [(AgentSpawnParams(visual_shape=BOX), 2)])
    with pytest.raises(ValueError, match="random generator"):
        manager.spawn_grid_counts(grid, [(AgentSpawnParams(visual_shape=BOX), 1)])
