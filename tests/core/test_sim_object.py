from __future__ import annotations

import logging
import math

import numpy as np
import pybullet as p
import pybullet_data
import pytest

from fleet_async import (
    CollisionMode,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimObject,
    SimObjectSpawnParams,
)
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def box(sim, x=0.0, y=0.0, z=0.5, **kw):
    return SimObject.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(x, y, z), sim_core=sim, **kw
    )


def pybullet_pose(sim, obj):
    pos, orn = p.getBasePositionAndOrientation(obj.body_id, physicsClientId=sim.client)
    return np.array(pos), np.array(orn)


# ----- shapes and spawn params -----------------------------------------------------------


def test_each_primitive_shape_spawns_with_its_geometry(sim):
    shapes = {
        "box": ShapeParams("box", half_extents=[0.2, 0.3, 0.4]),
        "sphere": ShapeParams("sphere", radius=0.25),
        "cylinder": ShapeParams("cylinder", radius=0.1, height=0.6),
    }
    for i, (kind, shape) in enumerate(shapes.items()):
        obj = SimObject.from_mesh(
            collision_shape=shape, visual_shape=shape, pose=Pose.from_xyz(5 * i, 0, 1), sim_core=sim
        )
        lo, hi = p.getAABB(obj.body_id, physicsClientId=sim.client)
        size = np.array(hi) - np.array(lo)
        expected = {"box": [0.4, 0.6, 0.8], "sphere": [0.5, 0.5, 0.5], "cylinder": [0.2, 0.2, 0.6]}[
            kind
        ]
        assert np.allclose(size, expected, atol=0.03), kind


def test_mesh_shape_and_shared_cache(sim):
    mesh = ShapeParams("mesh", mesh_path="cube.obj", mesh_scale=[0.5, 0.5, 0.5])
    a = SimObject.from_mesh(visual_shape=mesh, collision_shape=mesh, sim_core=sim)
    b = SimObject.from_mesh(
        visual_shape=mesh, collision_shape=mesh, pose=Pose.from_xyz(3, 0, 0), sim_core=sim
    )
    ids_a = SimObject.create_shared_shapes(mesh, mesh, physics_client_id=sim.client)
    ids_b = SimObject.create_shared_shapes(mesh, mesh, physics_client_id=sim.client)
    assert ids_a == ids_b and min(ids_a) >= 0
    assert (
        p.getCollisionShapeData(a.body_id, -1, physicsClientId=sim.client)[0][4]
        == p.getCollisionShapeData(b.body_id, -1, physicsClientId=sim.client)[0][4]
    )


def test_frame_offsets_shift_the_shape(sim):
    shape = ShapeParams("box", half_extents=[0.1, 0.1, 0.1], frame_pose=Pose.from_xyz(0, 0, 1.0))
    obj = SimObject.from_mesh(collision_shape=shape, sim_core=sim)
    lo, hi = p.getAABB(obj.body_id, physicsClientId=sim.client)
    assert math.isclose((lo[2] + hi[2]) / 2, 1.0, abs_tol=0.01)
    params = SimObjectSpawnParams(
        collision_shape=BOX, collision_frame_pose=Pose.from_xyz(2.0, 0, 0)
    )
    moved = SimObject.from_params(params, sim)
    lo, hi = p.getAABB(moved.body_id, physicsClientId=sim.client)
    assert math.isclose((lo[0] + hi[0]) / 2, 2.0, abs_tol=0.01)


def test_missing_mesh_names_the_path_and_loses_nothing(sim):
    keep = box(sim)
    shape = ShapeParams("mesh", mesh_path="no/such/mesh.obj")
    with pytest.raises(FileNotFoundError, match=r"no/such/mesh.obj"):
        SimObject.from_mesh(visual_shape=shape, sim_core=sim)
    assert sim.sim_objects == [keep]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"shape_type": "cone"}, "shape_type.*cone"),
        ({"shape_type": "mesh"}, "mesh_path"),
        ({"shape_type": "box", "half_extents": [1, 1]}, "half_extents"),
        ({"shape_type": "box", "half_extents": [1, 1, 0]}, "half_extents"),
        ({"shape_type": "sphere", "radius": -1}, "radius"),
        ({"rgba_color": [1, 0, 0]}, "rgba_color"),
        ({"rgba_color": [2, 0, 0, 1]}, "rgba_color"),
    ],
)
def test_bad_shape_params(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ShapeParams(**kwargs)


def test_shape_params_from_dict():
    shape = ShapeParams.from_dict({"shape_type": "cylinder", "radius": 0.2, "height": 0.5})
    assert (shape.shape_type, shape.radius, shape.height) == ("cylinder", 0.2, 0.5)
    with pytest.raises(ValueError, match=r"radis.*radius"):
        ShapeParams.from_dict({"shape_type": "sphere", "radis": 0.2})


def test_spawn_params_from_yaml_style_dict(sim):
    params = SimObjectSpawnParams.from_dict(
        {
            "name": "pallet",
            "visual_shape": {"shape_type": "box", "half_extents": [0.3, 0.3, 0.1]},
            "pose": [1, 2, 0.1],
            "yaw": math.pi / 2,
            "mass": 0.0,
            "collision_mode": "static",
            "user_data": {"sku": 7},
        }
    )
    assert params.name == "pallet" and params.collision_mode is CollisionMode.STATIC
    assert np.allclose(params.initial_pose.position, [1, 2, 0.1])
    assert math.isclose(params.initial_pose.yaw, math.pi / 2)
    obj = SimObject.from_dict(
        {
            "name": "crate",
            "collision_shape": {"shape_type": "sphere", "radius": 0.1},
            "pose": [3, 0, 0],
        },
        sim,
    )
    assert obj.name == "crate" and obj.get_pose().x == 3.0


@pytest.mark.parametrize(
    ("config", "match"),
    [
        ({"pose": [1, 2]}, "pose.*1, 2"),
        ({"mass": -1}, "mass.*-1"),
        ({"collision_mode": "solid"}, "collision_mode.*solid"),
        ({"colour": [1, 0, 0, 1]}, "colour"),
        ({}, "missing required 'name'"),
    ],
)
def test_bad_spawn_config(config, match):
    config = {"name": "box", **config} if config else config
    with pytest.raises(ValueError, match=match):
        SimObjectSpawnParams.from_dict(config)


def test_from_sdf_wraps_each_body(sim):
    shelves = SimObject.from_sdf("kiva_shelf/model.sdf", sim_core=sim, collision_mode="static")
    assert len(shelves) == 1
    shelf = shelves[0]
    assert (
        shelf.name == "model" and shelf.is_static and shelf.pickable is False and shelf.mass == 0.0
    )
    assert sim.sim_objects == shelves
    with pytest.raises(FileNotFoundError, match=r"missing.sdf"):
        SimObject.from_sdf("missing.sdf", sim_core=sim)


# ----- identity, pose ---------------------------------------------------------------------


def test_identity_fields(sim):
    obj = box(sim, name="A", user_data={"k": 1}, pickable=False)
    assert (obj.object_id, obj.name, obj.user_data, obj.pickable, obj.mass) == (
        0,
        "A",
        {"k": 1},
        False,
        0.0,
    )
    obj.set_name("B")
    assert obj.name == "B" and "B" in repr(obj)


def test_get_pose_reads_the_store_and_set_pose_reports_change(sim):
    obj = box(sim, x=1, y=2, z=3)
    assert obj.get_pose() == Pose.from_xyz(1, 2, 3)
    target = Pose.from_euler(4, 5, 6, yaw=0.5)
    assert obj.set_pose(target) is True
    assert obj.set_pose(target) is False
    assert obj.get_pose() == target
    pos, orn = pybullet_pose(sim, obj)  # outside a step: written through immediately
    assert np.allclose(pos, [4, 5, 6]) and np.allclose(orn, target.orientation)
    pose = obj.get_pose()
    pose.position[0] = 99  # a copy: mutating it does not move the object
    assert obj.get_pose().x == 4


@pytest.mark.parametrize(
    ("position", "orientation", "match"),
    [
        ([1, 2], [0, 0, 0, 1], "position.*1, 2"),
        ([1, 2, float("nan")], [0, 0, 0, 1], "position"),
        ([1, 2, 3], [0, 0, 0, 0], "zero quaternion"),
        ([1, 2, 3], [0, 0, 1], "orientation"),
    ],
)
def test_set_pose_raw_validates(sim, position, orientation, match):
    obj = box(sim, x=7)
    with pytest.raises(ValueError, match=match):
        obj.set_pose_raw(position, orientation)
    assert obj.get_pose().x == 7


def test_set_pose_needs_a_pose(sim):
    with pytest.raises(TypeError, match="Pose"):
        box(sim).set_pose([1, 2, 3])  # type: ignore[arg-type]


# ----- attachments ------------------------------------------------------------------------


def test_attached_child_follows_parent_in_the_same_step(sim):
    robot, pallet = box(sim), box(sim, x=3)
    assert robot.attach_object(pallet, relative_pose=Pose.from_xyz(0.5, 0, 0.2)) is True
    assert np.allclose(pallet.get_pose().position, [0.5, 0, 0.7])
    assert (
        pallet.is_attached()
        and robot.get_attached_objects() == [pallet]
        and robot.attached_objects == [pallet]
    )
    seen = []

    def drive(s, dt):
        robot.set_pose(Pose.from_euler(s.step_count + 1.0, 0, 0.5, yaw=math.pi / 2))

    sim.register_callback(drive)
    sim.register_callback(lambda s, dt: seen.append(pallet.get_pose().position.copy()))
    sim.step_once()
    # the child is where the parent puts it in the step the parent moved (rotated by yaw 90 deg)
    assert np.allclose(seen[-1], [1.0, 0.5, 0.7])
    sim.step_once()
    assert np.allclose(pallet.get_pose().position, [2.0, 0.5, 0.7])


def test_nested_attachments_follow_in_order(sim):
    a, b, c = box(sim), box(sim), box(sim)
    a.attach_object(b, relative_pose=Pose.from_xyz(1, 0, 0))
    b.attach_object(c, relative_pose=Pose.from_xyz(0, 1, 0))
    sim.register_callback(lambda s, dt: a.set_pose(Pose.from_xyz(10, 0, 0)))
    sim.step_once()
    assert np.allclose(c.get_pose().position, [11, 1, 0])


def test_keep_world_pose_and_link_attachment(sim, caplog):
    r2d2 = SimObject(p.loadURDF("r2d2.urdf", [0, 0, 0.5], physicsClientId=sim.client), sim_core=sim)
    item = box(sim, x=0.3, y=0.1, z=1.2)
    before = item.get_pose()
    r2d2.attach_object(item, parent_link_index="head", keep_world_pose=True)
    assert np.allclose(item.get_pose().position, before.position, atol=1e-9)
    r2d2.set_pose(Pose.from_xyz(2, 0, 0.5))
    assert np.allclose(item.get_pose().position, before.position + np.array([2, 0, 0]), atol=1e-9)
    # Seed, attach_object: "True if attachment successful, False otherwise" (logged, naming
    # the links the body has).
    loose = box(sim)
    with caplog.at_level(logging.WARNING):
        assert r2d2.attach_object(loose, parent_link_index="no_such_link") is False
    assert "no_such_link" in caplog.text and "'head'" in caplog.text
    assert not loose.is_attached()


@pytest.mark.parametrize(
    ("case", "standalone"),
    [("duplicate", False), ("other_parent", False), ("not_pickable", False), ("duplicate", True)],
)
def test_attach_returns_false_with_a_warning_like_the_seed(sim, caplog, case, standalone):
    owner = None if standalone else sim
    a, b, c = box(owner), box(owner), box(owner)
    fixed = box(owner, pickable=False)
    a.attach_object(b)
    parent, child, match = {
        "duplicate": (a, b, "already attached to this object"),
        "other_parent": (c, b, "already attached to SimObject"),
        "not_pickable": (a, fixed, "is not pickable"),
    }[case]
    with caplog.at_level(logging.WARNING):
        assert parent.attach_object(child) is False
    assert match in caplog.text
    assert a.get_attached_objects() == [b] and not c.is_attached() and not fixed.is_attached()


@pytest.mark.parametrize("case", ["self", "cycle", "both_poses", "joint_type"])
def test_bad_attach_raises_and_keeps_state(sim, case):
    a, b, c = box(sim), box(sim), box(sim)
    a.attach_object(b)
    args = {
        "self": (a, a, {}, "itself"),
        "cycle": (b, a, {}, "cycle"),
        "both_poses": (
            a,
            c,
            {"relative_pose": Pose.from_xyz(1, 0, 0), "keep_world_pose": True},
            "not both",
        ),
        "joint_type": (a, c, {"joint_type": p.JOINT_PRISMATIC}, "JOINT_FIXED"),
    }[case]
    parent, child, kwargs, match = args
    with pytest.raises(ValueError, match=match):
        parent.attach_object(child, **kwargs)
    assert a.get_attached_objects() == [b] and not c.is_attached()


def test_detach_variants(sim):
    robot, pallet = box(sim), box(sim)
    robot.attach_object(pallet, relative_pose=Pose.from_xyz(1, 0, 0))
    assert robot.detach_object(pallet) is True
    assert not pallet.is_attached() and np.allclose(pallet.get_pose().position, [1, 0, 0.5])
    robot.set_pose(Pose.from_xyz(5, 5, 5))
    assert np.allclose(pallet.get_pose().position, [1, 0, 0.5])  # no longer follows
    robot.attach_object(pallet)
    assert robot.detach_object(pallet, drop_pose=Pose.from_xyz(9, 9, 0.1)) is True
    assert pallet.get_pose() == Pose.from_xyz(9, 9, 0.1)
    robot.attach_object(pallet)
    assert robot.detach_object(pallet, drop_relative_pose=Pose.from_xyz(0, 0, -0.5)) is True
    assert np.allclose(pallet.get_pose().position, [5, 5, 4.5])
    assert robot.detach_object(pallet) is False
    with pytest.raises(ValueError, match="not both"):
        robot.detach_object(
            pallet, drop_pose=Pose.from_xyz(0, 0, 0), drop_relative_pose=Pose.from_xyz(0, 0, 0)
        )


def test_removing_a_parent_leaves_children_in_place(sim):
    robot, pallet = box(sim), box(sim)
    robot.attach_object(pallet, relative_pose=Pose.from_xyz(1, 0, 0))
    sim.remove_object(robot)
    assert not pallet.is_attached() and np.allclose(pallet.get_pose().position, [1, 0, 0.5])
    sim.step_once()


def test_dynamic_child_is_carried_kinematically_under_physics():
    with MultiRobotSimulationCore(headless_params(physics=True, enable_floor=False)) as psim:
        carrier = box(psim, z=2.0)
        crate = box(psim, x=3, z=2.0, mass=1.0)
        carrier.attach_object(crate, relative_pose=Pose.from_xyz(0, 0, 0.3))
        for _ in range(10):
            psim.step_once()
        assert np.allclose(crate.get_pose().position, [0, 0, 2.3])  # gravity does not pull it off
        carrier.detach_object(crate)
        for _ in range(10):
            psim.step_once()
        assert crate.get_pose().z < 2.29  # dynamic again: it falls (onto the carrier)


def test_find_nearest_pickable(sim):
    robot = box(sim)
    near = box(sim, x=0.5)
    box(sim, x=0.3, pickable=False)
    box(sim, x=5)
    assert robot.find_nearest_pickable(search_radius=1.0) is near
    robot.attach_object(near)
    assert robot.find_nearest_pickable(search_radius=1.0) is None


# ----- collision mode, callbacks, events ---------------------------------------------------


def test_collision_mode_changes(sim):
    obj = box(sim)
    assert obj.collision_mode is CollisionMode.NORMAL_3D and not obj.is_static
    obj.set_collision_mode("static")
    assert obj.is_static and sim.state.collision_mode[obj.state_row] == 2
    with pytest.raises(ValueError, match=r"collision_mode.*solid"):
        obj.set_collision_mode("solid")


def test_disabled_objects_make_no_physics_contact():
    with MultiRobotSimulationCore(headless_params(physics=True, enable_floor=False)) as psim:
        ghost = box(psim, z=0.0, mass=1.0, collision_mode=CollisionMode.DISABLED)
        other = box(psim, z=0.15, mass=1.0)
        psim.step_once()
        assert p.getContactPoints(ghost.body_id, other.body_id, physicsClientId=psim.client) == ()
        ghost.set_collision_mode(CollisionMode.NORMAL_2D)
        other.set_pose(Pose.from_xyz(0, 0, ghost.get_pose().z + 0.15))
        psim.step_once()
        assert (
            len(p.getContactPoints(ghost.body_id, other.body_id, physicsClientId=psim.client)) > 0
        )


def test_object_callbacks_run_at_their_frequency(sim):
    obj = box(sim)
    calls = []
    obj.register_callback(lambda o, dt: calls.append((sim.step_count, round(dt, 9))), frequency=2.5)
    for _ in range(9):
        sim.step_once()
    assert calls == [(4, 0.4), (8, 0.4)]
    with pytest.raises(ValueError, match="frequency"):
        obj.register_callback(lambda o, dt: None, frequency=0)


def test_update_override_runs_every_step(sim):
    class Spinner(SimObject):
        def update(self, dt):
            pose = self.get_pose()
            self.set_pose(Pose.from_euler(pose.x + dt, 0, 0))

    body = p.createMultiBody(0, -1, -1, [0, 0, 0], physicsClientId=sim.client)
    spinner = Spinner(body, sim_core=sim)
    for _ in range(10):
        sim.step_once()
    assert math.isclose(spinner.get_pose().x, 1.0)


def test_per_entity_event_bus_is_lazy(sim):
    obj = box(sim)
    assert obj.has_event_bus() is False
    got = []
    obj.events.on("custom", lambda **kw: got.append(kw))
    obj.events.emit("custom", value=1)
    assert obj.has_event_bus() and got == [{"value": 1}]


# ----- determinism --------------------------------------------------------------------------


def _scenario_trace(seed):
    with MultiRobotSimulationCore(headless_params(seed=seed)) as run:
        objs = [box(run, x=i, y=0) for i in range(5)]
        objs[0].attach_object(objs[1], relative_pose=Pose.from_xyz(0, 0, 0.3))

        def wander(s, dt):
            for obj in (objs[0], objs[2], objs[3], objs[4]):
                step = s.rng.normal(0.0, 0.2, size=3)
                pose = obj.get_pose()
                obj.set_pose(
                    Pose.from_euler(*(pose.position + step * dt), yaw=pose.yaw + s.rng.normal())
                )

        run.register_callback(wander)
        trace = []
        for _ in range(200):
            run.step_once()
            trace.append(run.get_poses([o.object_id for o in objs]))
        return trace


def test_same_seed_gives_identical_poses_step_by_step():
    first, second = _scenario_trace(3), _scenario_trace(3)
    assert len(first) == len(second) == 200
    for (pos_a, orn_a), (pos_b, orn_b) in zip(first, second, strict=True):
        assert np.array_equal(pos_a, pos_b) and np.array_equal(orn_a, orn_b)
    other = _scenario_trace(4)
    assert not np.array_equal(first[-1][0], other[-1][0])


def test_pybullet_data_path_is_searched(sim):
    assert pybullet_data.getDataPath()
    obj = SimObject.from_mesh(visual_shape=ShapeParams("mesh", mesh_path="duck.obj"), sim_core=sim)
    assert obj.body_id >= 0


def test_batch_spawned_bodies_can_be_picked_up_and_carry(sim):
    # One createMultiBody(batchPositions=...) call makes every body, but PyBullet's client
    # cache only knows the last one until it is refreshed; attach must work on all of them.
    params = [
        SimObjectSpawnParams(visual_shape=BOX, collision_shape=BOX, initial_pose=Pose([i, 0, 0.1]))
        for i in range(4)
    ]
    objs = SimObject.spawn_batch(params, sim)
    carrier = box(sim, 0.0, 3.0, 0.1)
    for k, obj in enumerate(objs):
        carrier.attach_object(obj, relative_pose=Pose([0, 0, 0.2 * (k + 1)]))
        obj.attach_object(box(sim, 10.0 + k, 0.0, 0.1), relative_pose=Pose([0, 0, 0.2]))
    got = np.array([o.get_pose().position for o in objs])
    assert np.allclose(got, [[0, 3, 0.3], [0, 3, 0.5], [0, 3, 0.7], [0, 3, 0.9]])


@pytest.mark.parametrize(
    ("pose", "expected_yaw"),
    [
        ({"position": [1, 2, 0.1], "rpy": [0, 0, 0.5]}, 0.5),
        ({"position": [1, 2, 0.1], "yaw": 0.25}, 0.25),
        ([1, 2, 0.1], 0.0),
    ],
)
def test_config_poses_accept_rpy_yaw_or_a_list(sim, pose, expected_yaw):
    box = {"shape_type": "box", "half_extents": [0.1, 0.1, 0.1]}
    cfg = {"name": "box", "visual_shape": box, "pose": pose}
    obj = SimObject.from_dict(cfg, sim)
    assert obj.get_pose().position.tolist() == pytest.approx([1, 2, 0.1])
    assert obj.get_pose().yaw == pytest.approx(expected_yaw)


def test_config_pose_rejects_two_orientations(sim):
    cfg = {"name": "box", "pose": {"position": [0, 0, 0], "rpy": [0, 0, 1], "yaw": 1.0}}
    with pytest.raises(ValueError, match="give one of 'orientation', 'yaw' or 'rpy'"):
        SimObject.from_dict(cfg, sim)
    with pytest.raises(ValueError, match=r"pose\.rpy: expected 3 finite numbers"):
        SimObject.from_dict({"name": "box", "pose": {"rpy": [0, 1]}}, sim)
