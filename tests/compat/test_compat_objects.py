"""Seed behaviours of SimObject, spawn parameters and URDF agents (issue 15); each test quotes
the seed text it checks."""

from __future__ import annotations

import logging

import pybullet as p
import pytest

from fleet_async.agent import Agent, AgentSpawnParams
from fleet_async.core_simulation import MultiRobotSimulationCore
from fleet_async.geometry import Pose
from fleet_async.sim_object import ShapeParams, SimObject, SimObjectSpawnParams
from fleet_async.types import CollisionMode
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


@pytest.fixture
def client():
    """A bare PyBullet client (0 when nothing else is connected), for objects without a sim."""
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(cid)


def body(x, client):
    shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=[0.1, 0.1, 0.1], physicsClientId=client)
    return p.createMultiBody(
        baseMass=0, baseCollisionShapeIndex=shape, basePosition=[x, 0, 0.1], physicsClientId=client
    )


# SimObject: "Supports attachment/detachment"; attach_object / detach_object: "True if ...
# successful, False otherwise"; SimObject(body_id, sim_core=None).


def test_objects_without_a_simulation_carry_each_other(client):
    assert client == 0  # objects without a simulation talk to the default client
    parent = SimObject(body(0, client), sim_core=None)
    child = SimObject(body(2, client), sim_core=None)
    assert (parent.object_id, child.object_id) == (-1, -1)
    assert parent.get_pose().position.tolist() == [0.0, 0.0, 0.1]
    assert parent.attach_object(child, relative_pose=Pose.from_xyz(0.5, 0, 0)) is True
    assert parent.get_attached_objects() == [child] and child.get_attached_parent() is parent
    assert child.is_attached()
    assert child.get_pose().position.tolist() == [0.5, 0.0, 0.1]
    assert parent.set_pose(Pose.from_xyz(1, 0, 0.1)) is True
    assert child.get_pose().position.tolist() == [1.5, 0.0, 0.1]
    pb = p.getBasePositionAndOrientation(child.body_id, physicsClientId=client)[0]
    assert list(pb) == pytest.approx([1.5, 0.0, 0.1])
    assert parent.detach_object(child, drop_pose=Pose.from_xyz(3, 3, 0.1)) is True
    assert child.get_pose().position.tolist() == [3.0, 3.0, 0.1] and not child.is_attached()
    assert parent.detach_object(child) is False
    assert parent.attach_object(child)
    with pytest.raises(ValueError, match="cycle"):
        child.attach_object(parent)


def test_an_object_keeps_its_own_pose_until_add_object(sim):
    obj = SimObject(body(1, sim.client), sim_core=None)
    assert obj.set_pose(Pose.from_xyz(4, 0, 0.1))
    sim.add_object(obj)
    assert obj.object_id == 0 and obj.get_pose().position.tolist() == [4.0, 0.0, 0.1]
    pb = p.getBasePositionAndOrientation(obj.body_id, physicsClientId=sim.client)[0]
    assert list(pb) == pytest.approx([4.0, 0.0, 0.1])
    assert obj.set_pose(Pose.from_xyz(5, 0, 0.1)) and obj.get_pose().x == 5.0


def test_an_attachment_made_outside_joins_the_simulation_with_both_ends(sim):
    parent = SimObject(body(0, sim.client), sim_core=None)
    child = SimObject(body(2, sim.client), sim_core=None)
    parent.attach_object(child, relative_pose=Pose.from_xyz(0, 0, 0.3))
    sim.add_object(parent)
    assert child.get_attached_parent() is parent  # waits on the end still outside
    sim.add_object(child)
    assert parent.get_attached_objects() == [child]
    parent.set_pose(Pose.from_xyz(2, 0, 0.1))
    assert child.get_pose().position.tolist() == pytest.approx([2.0, 0.0, 0.4])


# CollisionMode.STATIC: "Static object mode (never moves, but has collision)".


def test_a_static_object_refuses_set_pose_until_its_mode_changes(sim, caplog):
    shelf = SimObject.from_mesh(
        BOX, BOX, Pose.from_xyz(1, 0, 0.1), sim_core=sim, collision_mode=CollisionMode.STATIC
    )
    with caplog.at_level(logging.WARNING):
        assert shelf.set_pose(Pose.from_xyz(2, 0, 0.1)) is False
    assert "STATIC" in caplog.text and shelf.get_pose().x == 1.0
    pb = p.getBasePositionAndOrientation(shelf.body_id, physicsClientId=sim.client)[0]
    assert pb[0] == pytest.approx(1.0)
    shelf.set_collision_mode(CollisionMode.NORMAL_3D)
    assert shelf.set_pose(Pose.from_xyz(2, 0, 0.1)) is True and shelf.get_pose().x == 2.0


def test_is_kinematic_means_massless(sim):
    crate = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, mass=2.0)
    assert not crate.is_kinematic
    assert SimObject.from_mesh(BOX, BOX, Pose.from_xyz(1, 0, 0.1), sim_core=sim).is_kinematic
    assert SimObject(-1, sim_core=None, mass=0.0).is_kinematic
    assert not SimObject(-1, sim_core=None, mass=1.0).is_kinematic


# Agent.from_urdf: "mass ... None (default): Use URDF file's mass values as-is; 0.0: Override
# all links to mass=0 for kinematic control (no physics)".


def test_from_urdf_mass_none_keeps_and_reports_the_urdf_masses(sim):
    kuka = Agent.from_urdf("kuka_iiwa", use_fixed_base=True, sim_core=sim)
    links = [p.getDynamicsInfo(kuka.body_id, i, physicsClientId=sim.client)[0] for i in range(7)]
    assert links == pytest.approx([4.0, 4.0, 3.0, 2.7, 1.7, 1.8, 0.3])
    assert kuka.mass == pytest.approx(17.5)  # the URDF's total
    light = Agent.from_urdf("kuka_iiwa", use_fixed_base=True, mass=0.0, sim_core=sim)
    assert light.mass == 0.0 and light.is_kinematic and not kuka.is_kinematic
    assert p.getDynamicsInfo(light.body_id, 3, physicsClientId=sim.client)[0] == 0.0


# AgentSpawnParams(mass=None): pybullet_fleet 0.8.0 hands it to Agent.from_urdf, whose None
# keeps the URDF's own masses; for a mesh or virtual agent it fails when spawning (a TypeError
# from PyBullet), here when the parameters are made, naming the field.


@pytest.mark.parametrize("physics", [False, True])
def test_agent_spawn_params_mass_none_keeps_the_urdf_masses(physics):
    with MultiRobotSimulationCore(headless_params(physics=physics)) as sim:
        params = AgentSpawnParams(urdf_path="kuka_iiwa", use_fixed_base=True, mass=None)
        kuka = Agent.from_params(params, sim)
        links = [
            p.getDynamicsInfo(kuka.body_id, i, physicsClientId=sim.client)[0] for i in range(7)
        ]
        assert links == pytest.approx([4.0, 4.0, 3.0, 2.7, 1.7, 1.8, 0.3])
        assert kuka.mass == pytest.approx(17.5) and not kuka.is_kinematic
        config = {"urdf_path": "mobile_robot", "mass": None, "pose": [2, 0, 0.1]}
        rover = Agent.from_params(AgentSpawnParams.from_dict(config), sim)
        assert rover.mass > 0 and not rover.is_kinematic
        default = Agent.from_params(AgentSpawnParams(urdf_path="mobile_robot"), sim)
        assert default.mass == 0.0 and default.is_kinematic  # the default is still 0.0


def test_mass_none_without_a_urdf_is_refused():
    with pytest.raises(ValueError, match=r"AgentSpawnParams\.mass: None .*urdf_path") as info:
        AgentSpawnParams(visual_shape=BOX, collision_shape=BOX, mass=None)
    assert "mesh" in str(info.value)
    with pytest.raises(ValueError, match=r"AgentSpawnParams\.mass: None .*virtual"):
        AgentSpawnParams(mass=None)
    with pytest.raises(ValueError, match=r"SimObjectSpawnParams\.mass: .*None"):
        SimObjectSpawnParams(visual_shape=BOX, mass=None)


# SimObjectSpawnParams.from_dict: "name (str, required)"; "Raises: ValueError - If name is
# missing."; "initial_pose (Pose): Pose object (takes precedence over pose)".


def test_spawn_params_from_dict_requires_a_name():
    with pytest.raises(ValueError, match="missing required 'name'"):
        SimObjectSpawnParams.from_dict({"visual_shape": {"shape_type": "box"}})
    with pytest.raises(ValueError, match=r"scene\.yaml: .*missing required 'name'"):
        SimObjectSpawnParams.from_dict({"pose": [0, 0, 0]}, source="scene.yaml")
    # The seed's own AgentSpawnParams.from_dict examples have no name: optional for agents.
    assert AgentSpawnParams.from_dict({"urdf_path": "mobile_robot"}).name is None


def test_initial_pose_takes_precedence_over_pose(caplog):
    config = {"name": "crate", "pose": [1, 2, 3], "initial_pose": Pose.from_xyz(7, 7, 0)}
    with caplog.at_level(logging.WARNING):
        params = SimObjectSpawnParams.from_dict(config)
    assert params.initial_pose.position.tolist() == [7.0, 7.0, 0.0]
    assert "initial_pose takes precedence" in caplog.text
    agent = AgentSpawnParams.from_dict({"pose": [1, 2, 3], "initial_pose": Pose.from_xyz(7, 7, 0)})
    assert agent.initial_pose.position.tolist() == [7.0, 7.0, 0.0]
