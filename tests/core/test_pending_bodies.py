"""Bodies of objects spawned one at a time are created together, before anything needs them."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from fleet_async import (
    Agent,
    AgentSpawnParams,
    CollisionMode,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimObject,
)
from fleet_async.core.world.pending import PENDING_BODY
from tests.conftest import headless_params

CUBE = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def spawn(sim, x, **kw):
    return Agent.from_mesh(CUBE, CUBE, Pose.from_xyz(x, 0.0, 0.1), sim_core=sim, **kw)


def test_a_loop_of_from_mesh_leaves_bodies_pending_until_something_needs_them(sim):
    agents = [spawn(sim, float(i)) for i in range(5)]
    assert sim.world.has_pending_bodies
    assert [a.raw_body_id for a in agents] == [PENDING_BODY] * 5
    assert agents[2].get_pose().x == 2.0  # the row exists at once
    agents[3].set_goal_pose(Pose.from_xyz(3.0, 2.0, 0.1))
    for _ in range(30):
        sim.step_once()  # motion and collision checks need no PyBullet body
    assert agents[3].get_pose().y == pytest.approx(2.0)
    # Only the first body of the shape was made, to measure the shape.
    assert [a.raw_body_id == PENDING_BODY for a in agents] == [False] + [True] * 4
    bodies = [a.body_id for a in agents]  # reading one creates them all
    assert min(bodies) >= 0 and len(set(bodies)) == 5 and not sim.world.has_pending_bodies
    for a in agents:
        pos, _ = p.getBasePositionAndOrientation(a.body_id, physicsClientId=sim.client)
        assert pos == pytest.approx(a.get_pose().position)


def test_reading_body_id_or_the_client_creates_what_is_pending(sim):
    a, b = spawn(sim, 0.0), spawn(sim, 1.0)
    body = a.body_id  # creates both, and PyBullet's client knows both
    assert body >= 0 and b.raw_body_id >= 0
    assert p.getBodyInfo(b.raw_body_id, physicsClientId=sim.client)
    c = spawn(sim, 2.0)
    assert p.getNumBodies(physicsClientId=sim.client) == 3 + int(sim.params.enable_floor)
    assert c.raw_body_id >= 0 and p.getBodyInfo(c.body_id, physicsClientId=sim.client)


def test_bodies_are_made_where_the_objects_are_now(sim):
    rotated = SimObject.from_mesh(CUBE, CUBE, Pose.from_euler(0.0, 0.0, 0.1, yaw=0.7), sim_core=sim)
    moved = spawn(sim, 0.0)
    moved.set_pose(Pose.from_xyz(3.0, 4.0, 0.1))  # before the body exists
    sim.sync_pybullet()
    for obj in (rotated, moved):
        pos, orn = p.getBasePositionAndOrientation(obj.body_id, physicsClientId=sim.client)
        assert pos == pytest.approx(obj.get_pose().position)
        assert np.allclose(orn, obj.get_pose().orientation)


def test_an_object_removed_before_its_body_exists_never_gets_one(sim):
    keep, gone = spawn(sim, 0.0), spawn(sim, 1.0)
    sim.remove_object(gone)
    assert gone.body_id == -1
    sim.step_once()
    assert p.getNumBodies(physicsClientId=sim.client) == 1 + int(sim.params.enable_floor)
    assert keep.body_id >= 0
    spawn(sim, 2.0)
    sim.reset()
    assert not sim.world.has_pending_bodies


def test_disabled_objects_get_their_contact_filter_when_created(sim):
    ghost = spawn(sim, 0.0, collision_mode=CollisionMode.DISABLED)
    sim.step_once()
    info = p.getCollisionShapeData(ghost.body_id, -1, physicsClientId=sim.client)
    assert info  # the body exists; PyBullet reports no contacts for it below
    other = spawn(sim, 0.05)
    sim.step_once()
    p.performCollisionDetection(physicsClientId=sim.client)
    assert not p.getContactPoints(ghost.body_id, other.body_id, physicsClientId=sim.client)


def test_collisions_of_pending_bodies_are_found_in_the_first_step(sim):
    a, b = spawn(sim, 0.0), spawn(sim, 0.15)
    sim.step_once()
    assert sim.get_active_collision_pairs() == [(a.object_id, b.object_id)]


def test_bodies_are_made_at_once_with_dynamics_and_before_a_physics_step():
    with MultiRobotSimulationCore(headless_params(physics=True)) as sim:
        heavy = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(0, 0, 1), mass=1.0, sim_core=sim)
        light = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(1, 0, 1), mass=0.0, sim_core=sim)
        assert heavy.raw_body_id >= 0 and light.raw_body_id == PENDING_BODY
        sim.step_once()
        assert light.raw_body_id >= 0


def test_queries_that_need_bodies_create_them():
    with MultiRobotSimulationCore(
        headless_params(collision_detection_method="contact_points")
    ) as sim:
        a, b = spawn(sim, 0.0), spawn(sim, 0.19)
        sim.step_once()
        assert b.raw_body_id >= 0 and a.raw_body_id >= 0


def _loaded_spawn_loop(sim, n):
    """The issue-28 spawn loop: an agent with controllers and a battery, a tote of the same
    shape (so both wait in one creation group), the tote attached; then the first step."""
    for i in range(n):
        x = 2.0 * i
        params = AgentSpawnParams(
            visual_shape=CUBE,
            collision_shape=CUBE,
            initial_pose=Pose.from_xyz(x, 0.0, 0.1),
            controller=[
                {"type": "omni", "max_linear_vel": 2.0},
                {"type": "patrol", "waypoints": [[x, 0.0, 0.1], [x, 1.0, 0.1]]},
            ],
            plugins=[{"type": "battery"}],
        )
        robot = Agent.from_params(params, sim_core=sim)
        tote = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(x, 0.0, 0.4), sim_core=sim)
        assert robot.attach_object(tote, relative_pose=Pose.from_xyz(0.0, 0.0, 0.3))
    sim.step_once()


def _count_syncs(monkeypatch, work):
    calls = []
    real = p.syncBodyInfo

    def counting(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(p, "syncBodyInfo", counting)
    work()
    monkeypatch.setattr(p, "syncBodyInfo", real)
    return len(calls)


@pytest.mark.parametrize("read_body_ids", [False, True])
def test_body_list_syncs_do_not_grow_with_the_fleet(monkeypatch, read_body_ids):
    counts = []
    for n in (10, 40):
        sim = MultiRobotSimulationCore(headless_params())
        try:

            def work(sim=sim, n=n):
                _loaded_spawn_loop(sim, n)
                if read_body_ids:  # raw access, object by object, as user code does it
                    for _ in range(n):
                        robot = spawn(sim, -5.0)
                        assert p.getBodyInfo(robot.body_id, physicsClientId=sim.client)

            counts.append(_count_syncs(monkeypatch, work))
            assert all(o.raw_body_id != PENDING_BODY for o in sim.sim_objects) or not read_body_ids
        finally:
            p.disconnect(sim.client)
    assert counts[0] == counts[1] <= 1
