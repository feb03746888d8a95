"""Robots of one URDF model: parsed once, later robots wait for their bodies, and the bodies
they get are the ones ``loadURDF`` gives."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from fleet_async import Agent, MultiRobotSimulationCore, Pose
from fleet_async.core.bodies.models import resolve_model
from fleet_async.core.world.pending import PENDING_BODY
from tests.conftest import headless_params

# husky: mesh visuals, primitive collisions, fixed and continuous joints; the project's
# mobile manipulator: primitives, revolute and prismatic joints with limits; kuka_iiwa: mesh
# collisions and a base inertial frame off the link frame; r2d2: mesh visuals, many links.
MODELS = ["husky", "mobile_manipulator", "kuka_iiwa", "r2d2"]
POSES = [
    Pose.from_xyz(0.0, 0.0, 0.1),
    Pose.from_xyz(3.0, -2.0, 0.25),
    Pose.from_euler(-4.0, 5.0, 0.1, yaw=0.7),
    Pose.from_euler(6.0, 6.0, 0.3, roll=0.2, pitch=-0.1, yaw=-2.4),
]


def _reference(path: str, pose: Pose, mass: float | None) -> tuple[int, int]:
    """A body loaded with plain ``loadURDF`` in a client of its own, as the spawn always did."""
    client = p.connect(p.DIRECT)
    pos, orn = pose.as_position_orientation()
    body = p.loadURDF(
        path, pos, orn, flags=p.URDF_ENABLE_CACHED_GRAPHICS_SHAPES, physicsClientId=client
    )
    if mass == 0.0:
        for link in range(-1, p.getNumJoints(body, physicsClientId=client)):
            p.changeDynamics(body, link, mass=0.0, physicsClientId=client)
    return client, body


def _links(body: int, client: int) -> list[tuple]:
    n = p.getNumJoints(body, physicsClientId=client)
    return [
        p.getLinkState(body, j, computeForwardKinematics=1, physicsClientId=client)
        for j in range(n)
    ]


def _aabbs(body: int, client: int) -> list[tuple]:
    n = p.getNumJoints(body, physicsClientId=client)
    return [p.getAABB(body, j, physicsClientId=client) for j in range(-1, n)]


def _joint_infos(body: int, client: int) -> list[tuple]:
    n = p.getNumJoints(body, physicsClientId=client)
    # Field 0 is the body's own id in the client's list (always 0 there, any here): skip it.
    return [p.getJointInfo(body, j, physicsClientId=client)[1:] for j in range(n)]


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("mass", [0.0, None])
def test_robots_of_one_model_get_the_bodies_load_urdf_gives(model, mass):
    sim = MultiRobotSimulationCore(headless_params(enable_floor=False))
    try:
        agents = [Agent.from_urdf(model, pose=pose, mass=mass, sim_core=sim) for pose in POSES]
        assert [a.raw_body_id == PENDING_BODY for a in agents] == [False, True, True, True]
        path = resolve_model(model)
        for agent, pose in zip(agents, POSES, strict=True):
            client, ref = _reference(path, pose, mass)
            try:
                # The row holds PyBullet's base pose before any body exists: the same bits.
                pos, orn = p.getBasePositionAndOrientation(ref, physicsClientId=client)
                assert tuple(agent.get_pose().position) == pos
                assert tuple(agent.get_pose().orientation) == orn
                total = sum(
                    p.getDynamicsInfo(ref, j, physicsClientId=client)[0]
                    for j in range(-1, p.getNumJoints(ref, physicsClientId=client))
                )
                assert agent.mass == total
                body = agent.body_id  # the first pending one's creates every pending body
                assert _joint_infos(body, sim.client) == _joint_infos(ref, client)
                assert _links(body, sim.client) == _links(ref, client)
                assert np.allclose(_aabbs(body, sim.client), _aabbs(ref, client), atol=1e-12)
                assert p.getBodyInfo(body, physicsClientId=sim.client) == p.getBodyInfo(
                    ref, physicsClientId=client
                )
                for j in range(-1, p.getNumJoints(ref, physicsClientId=client)):
                    mine = p.getDynamicsInfo(body, j, physicsClientId=sim.client)
                    theirs = p.getDynamicsInfo(ref, j, physicsClientId=client)
                    assert mine[:5] == theirs[:5]  # mass, friction, inertia, inertial frame
            finally:
                p.disconnect(physicsClientId=client)
        assert not sim.world.has_pending_bodies
        limits = [(j.lower, j.upper, j.max_velocity) for j in agents[0].joints.infos]
        assert all(
            [(j.lower, j.upper, j.max_velocity) for j in a.joints.infos] == limits for a in agents
        )
    finally:
        sim.close()


@pytest.mark.parametrize("model", ["husky", "mobile_manipulator", "kuka_iiwa"])
def test_a_waiting_robot_is_bounded_by_the_box_its_body_will_have(model):
    sim = MultiRobotSimulationCore(headless_params(enable_floor=False))
    try:
        first = Agent.from_urdf(model, pose=Pose.from_xyz(0.0, 0.0, 0.1), mass=0.0, sim_core=sim)
        later = Agent.from_urdf(model, pose=Pose.from_xyz(5.0, 1.0, 0.1), mass=0.0, sim_core=sim)
        sim.step_once()  # registers both with the collision system
        assert later.raw_body_id == PENDING_BODY
        waiting = sim.get_aabbs()[later.object_id]
        sim.sync_pybullet()  # the body exists now: its AABB is read from PyBullet
        boxes = _aabbs(later.body_id, sim.client)
        lo = np.min([b[0] for b in boxes], axis=0)
        hi = np.max([b[1] for b in boxes], axis=0)
        assert np.allclose(waiting[0], lo, atol=1e-12)
        assert np.allclose(waiting[1], hi, atol=1e-12)
        assert first.object_id in sim.get_aabbs()
    finally:
        sim.close()


def test_a_fleet_of_one_model_loads_it_once_until_pybullet_is_needed(monkeypatch):
    loads: list[str] = []
    real = p.loadURDF

    def counting(path, *args, **kwargs):
        loads.append(path)
        return real(path, *args, **kwargs)

    monkeypatch.setattr(p, "loadURDF", counting)
    sim = MultiRobotSimulationCore(headless_params(enable_floor=False))
    try:
        robots = [
            Agent.from_urdf(
                "mobile_robot",
                pose=Pose.from_xyz(3.0 * (i % 5), 3.0 * (i // 5), 0.1),
                mass=0.0,
                sim_core=sim,
                controller="omni",
            )
            for i in range(20)
        ]
        robots[7].set_goal_pose(Pose.from_xyz(4.5, 4.0, 0.1))
        for _ in range(40):
            sim.step_once()  # motion and collision checks need no body
        assert robots[7].get_pose().position == pytest.approx([4.5, 4.0, 0.1], abs=1e-6)
        assert len(loads) == 1
        assert p.getNumBodies(physicsClientId=sim.world.client) == 1
        assert sim.step_count == 40
        body = robots[7].body_id  # raw access to one robot: its body is loaded, where it is
        assert len(loads) == 2
        assert robots[8].raw_body_id == PENDING_BODY
        pos, _ = p.getBasePositionAndOrientation(body, physicsClientId=sim.world.client)
        assert pos == tuple(robots[7].get_pose().position)
        assert robots[3].joint_names == robots[0].joint_names  # joints need the body
        assert len(loads) == 3
        client = sim.client  # raw access to the simulation: every body is loaded
        assert len(loads) == 20
        assert p.getNumBodies(physicsClientId=client) == 20
    finally:
        sim.close()


def test_waiting_robots_that_touch_are_reported_as_loaded_ones_are():
    def touching(defer: bool) -> list[tuple[int, int]]:
        sim = MultiRobotSimulationCore(headless_params(enable_floor=False))
        try:
            a = Agent.from_urdf("husky", pose=Pose.from_xyz(0.0, 0.0, 0.1), mass=0.0, sim_core=sim)
            b = Agent.from_urdf("husky", pose=Pose.from_xyz(0.9, 0.0, 0.1), mass=0.0, sim_core=sim)
            c = Agent.from_urdf("husky", pose=Pose.from_xyz(9.0, 0.0, 0.1), mass=0.0, sim_core=sim)
            if not defer:  # every body loaded before the collision system sees them
                sim.sync_pybullet()
            sim.step_once()
            # The pair a-b needed PyBullet's view: their bodies are loaded, not c's.
            assert b.raw_body_id != PENDING_BODY
            assert (c.raw_body_id == PENDING_BODY) == defer
            return [(a.object_id, b.object_id)] if sim.get_active_collision_pairs() else []
        finally:
            sim.close()

    assert touching(True) == touching(False) == [(0, 1)]


def test_joint_motion_of_a_waiting_robot_matches_the_first_one():
    sim = MultiRobotSimulationCore(headless_params(enable_floor=False))
    try:
        arms = [
            Agent.from_urdf(
                "mobile_manipulator", pose=Pose.from_xyz(3.0 * i, 0.0, 0.0), mass=0.0, sim_core=sim
            )
            for i in range(3)
        ]
        assert arms[2].raw_body_id == PENDING_BODY
        for arm in (arms[0], arms[2]):
            arm.set_joints_targets_by_name({"rail_joint": 0.2, "mount_to_shoulder": -0.5})
        for _ in range(12):
            sim.step_once()
        assert arms[2].get_all_joints_state() == arms[0].get_all_joints_state()
        # getLinkState gives link positions in single precision.
        far, near = arms[2].get_end_effector_pose()[0], arms[0].get_end_effector_pose()[0]
        assert list(far) == pytest.approx([near[0] + 6.0, near[1], near[2]], abs=1e-6)
    finally:
        sim.close()


def test_dynamic_robots_and_removed_ones_and_resets():
    sim = MultiRobotSimulationCore(headless_params(enable_floor=False, physics=True))
    try:
        Agent.from_urdf("mobile_robot", pose=Pose.from_xyz(0.0, 0.0, 0.3), sim_core=sim)
        heavy = Agent.from_urdf("mobile_robot", pose=Pose.from_xyz(2.0, 0.0, 0.3), sim_core=sim)
        light = Agent.from_urdf(
            "mobile_robot", pose=Pose.from_xyz(4.0, 0.0, 0.3), mass=0.0, sim_core=sim
        )
        assert heavy.raw_body_id >= 0  # with physics and masses: loaded at once, dynamic
        assert light.raw_body_id >= 0  # the first massless one of the model
        gone = Agent.from_urdf(
            "mobile_robot", pose=Pose.from_xyz(6.0, 0.0, 0.3), mass=0.0, sim_core=sim
        )
        assert gone.raw_body_id == PENDING_BODY
        sim.remove_object(gone)
        sim.sync_pybullet()
        assert gone.raw_body_id == -1
        assert p.getNumBodies(physicsClientId=sim.client) == 3
        sim.reset()
        again = Agent.from_urdf(
            "mobile_robot", pose=Pose.from_xyz(0.0, 0.0, 0.3), mass=0.0, sim_core=sim
        )
        assert again.raw_body_id >= 0  # the reset forgot the model: loaded for real again
        assert math.isclose(again.mass, 0.0)
    finally:
        sim.close()
