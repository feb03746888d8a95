"""The simulation as a pybullet_fleet script uses it (issue 15): the object registry names of
the seed's examples, and safe paths to PyBullet's view under lazy sync; pybullet_fleet 0.8.0's
behaviour where the seed is silent (issue 27): a paused simulation given to run_simulation and
the collision method SimulationParams reports."""

from __future__ import annotations

import time

import pybullet as p
import pytest

from fleet_async.agent import Agent
from fleet_async.core_simulation import MultiRobotSimulationCore, SimulationParams
from fleet_async.events import SimEvents
from fleet_async.geometry import Pose
from fleet_async.sim_object import ShapeParams, SimObject, SimObjectSpawnParams
from fleet_async.types import CollisionDetectionMethod
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def test_objects_and_the_sim_objects_dict_of_the_seed_examples(sim):
    # SimObjectSpawnParams example: pallets = [o for o in sim_core.objects if o.name == ...]
    params = SimObjectSpawnParams(
        visual_shape=BOX, collision_shape=BOX, initial_pose=Pose.from_xyz(0, 0, 1), name="Pallet_A"
    )
    obj = SimObject.from_params(params, sim)
    other = SimObject.from_params(params, sim)
    assert [o for o in sim.objects if o.name == "Pallet_A"] == [obj, other]
    assert sim.objects == sim.sim_objects
    # get_active_collision_pairs example: obj_i = sim_core._sim_objects_dict[obj_id_i]
    sim.step_once()
    pairs = sim.get_active_collision_pairs()
    assert pairs == [(obj.object_id, other.object_id)]
    view = sim._sim_objects_dict  # the seed's documented example
    assert [view[i] for i in pairs[0]] == [obj, other]
    with pytest.raises(TypeError):
        view[99] = obj  # read-only
    sim.remove_object(other)
    assert other.object_id not in view  # a live view


def _pybullet_x(sim, obj):
    return p.getBasePositionAndOrientation(obj.body_id, physicsClientId=sim.client)[0][0]


def test_pybullet_lags_a_kinematic_fleet_until_asked(sim):
    robot = Agent.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")
    robot.set_goal_pose(Pose.from_xyz(1, 0, 0.1))
    for _ in range(3):
        sim.step_once()
    assert robot.get_pose().x == pytest.approx(0.225)
    # Lazy: PyBullet last saw the robot when the collision system first measured it.
    assert _pybullet_x(sim, robot) == pytest.approx(0.025)
    assert sim.sync_pybullet() == 1
    assert _pybullet_x(sim, robot) == pytest.approx(0.225)
    assert sim.sync_pybullet() == 0


def test_sync_pybullet_every_step_keeps_pybullet_current():
    with MultiRobotSimulationCore(headless_params(sync_pybullet_every_step=True)) as sim:
        robot = Agent.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")
        marker = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(5, 0, 0.1), sim_core=sim)
        robot.set_goal_pose(Pose.from_xyz(1, 0, 0.1))

        def move_marker(sim, **_):  # a pose written by a POST_STEP handler, inside the step
            marker.set_pose(Pose.from_xyz(5 + sim.step_count, 0, 0.1))

        sim.events.on("post_step", move_marker)
        for _ in range(3):
            sim.step_once()
            assert _pybullet_x(sim, robot) == robot.get_pose().x
            assert _pybullet_x(sim, marker) == marker.get_pose().x
        assert "phase2_pose_flush" in sim.step_once(return_profiling=True)


def test_ray_tests_see_poses_written_inside_the_step(sim):
    wall = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim)
    assert wall.body_id >= 0  # its body exists (else the raw call below creates it, up to date)
    hits = {}

    def probe(sim, dt):
        wall.set_pose(Pose.from_xyz(3, 0, 0.1))  # stays in the state store for now
        ray = ([3, -2, 0.1], [3, 2, 0.1])
        raw = p.rayTest(*ray, physicsClientId=sim.client)[0][0]
        hits["raw"] = raw
        hits["ray_test"] = sim.ray_test(*ray)[0][0]
        hits["batch"] = [
            h[0] for h in sim.ray_test_batch([ray[0], [0, -2, 0.1]], [ray[1], [0, 2, 0.1]])
        ]

    sim.register_callback(probe)
    sim.step_once()
    assert hits == {"raw": -1, "ray_test": wall.body_id, "batch": [wall.body_id, -1]}
    with pytest.raises(ValueError, match="rays_to"):
        sim.ray_test_batch([[0, 0, 0]], [])


# pybullet_fleet 0.8.0 resumes a paused simulation when run_simulation starts (its
# initialize_simulation calls resume()), so a headless run after sim.pause() runs and returns.


def test_run_simulation_resumes_a_paused_simulation(sim, monkeypatch):
    def no_waiting(seconds):  # the paused run loop's only wall-clock call: a hang, made a failure
        raise AssertionError(f"run_simulation waited {seconds} s for someone to resume it")

    monkeypatch.setattr(time, "sleep", no_waiting)
    resumed_at = []
    sim.events.on(SimEvents.RESUMED, lambda sim, **_: resumed_at.append(sim.step_count))
    for _ in range(3):
        sim.step_once()
    sim.pause()
    sim.run_simulation(duration=1.0)
    assert resumed_at == [3] and not sim.is_paused
    assert sim.step_count == 13 and sim.sim_time == 13 * 0.1


# SimulationParams.collision_detection_method: None means "pick by physics"; pybullet_fleet 0.8.0
# stores the method it picked, so the field reports the method in force.


def test_collision_detection_method_reports_the_method_in_force():
    closest = CollisionDetectionMethod.CLOSEST_POINTS
    contact = CollisionDetectionMethod.CONTACT_POINTS
    assert SimulationParams(gui=False).collision_detection_method is closest
    assert SimulationParams(gui=False, physics=True).collision_detection_method is contact
    assert SimulationParams.from_dict({"physics": True}).collision_detection_method is contact
    explicit = SimulationParams(physics=True, collision_detection_method="hybrid")
    assert explicit.collision_detection_method is CollisionDetectionMethod.HYBRID
    with MultiRobotSimulationCore(headless_params(physics=True)) as sim:
        assert sim.params.collision_detection_method is contact
