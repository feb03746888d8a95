"""Collision detection: modes, methods, events, frequency, and the broad phase vs brute force."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from fleet_async import (
    Agent,
    CollisionMode,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    SimObjectSpawnParams,
    SpatialHashCellSizeMode,
)
from fleet_async.core.collision.broadphase import aabb_overlap, candidate_pairs
from tests.conftest import headless_params

HALF = 0.1
CUBE = ShapeParams("box", half_extents=[HALF, HALF, HALF])


def cube(sim, x, y=0.0, z=0.5, mode=CollisionMode.NORMAL_3D, **kw):
    return SimObject.from_mesh(
        CUBE, CUBE, Pose.from_xyz(x, y, z), sim_core=sim, collision_mode=mode, **kw
    )


def make_sim(**overrides):
    return MultiRobotSimulationCore(headless_params(enable_floor=False, **overrides))


@pytest.mark.parametrize("gap", [0.0, 0.015, 0.025, 0.5])
@pytest.mark.parametrize("mode", [CollisionMode.NORMAL_3D, CollisionMode.NORMAL_2D])
def test_closest_points_uses_the_margin(gap, mode):
    with make_sim(collision_margin=0.02) as sim:
        a, b = cube(sim, 0.0, mode=mode), cube(sim, 2 * HALF + gap, mode=mode)
        pairs, _ = sim.check_collisions()
        expected = [(a.object_id, b.object_id)] if gap <= 0.02 else []
        assert pairs == expected


@pytest.mark.parametrize("method", ["closest_points", "hybrid"])
def test_static_and_disabled_modes(method):
    with make_sim(collision_detection_method=method, ignore_static_collision=False) as sim:
        wall = cube(sim, 0.0, mode=CollisionMode.STATIC)
        other_wall = cube(sim, 0.2, mode=CollisionMode.STATIC)
        ghost = cube(sim, 0.0, y=0.2, mode=CollisionMode.DISABLED)
        robot = cube(sim, 0.1, y=0.2)
        pairs, _ = sim.check_collisions()
        # The robot touches both walls; with ignore_static_collision=False the two overlapping
        # walls are reported too (seed, filter_aabb_pairs: "ignore_static - If True, skip
        # collision checks with static objects"); the ghost pairs with nobody.
        assert pairs == sorted(
            [
                (wall.object_id, other_wall.object_id),
                (wall.object_id, robot.object_id),
                (other_wall.object_id, robot.object_id),
            ]
        )
        assert all(ghost.object_id not in pair for pair in pairs)
        robot.set_pose(Pose.from_xyz(5.0, 0.2, 0.5))
        pairs, _ = sim.check_collisions()  # the walls never move: their pair stays active
        assert pairs == [(wall.object_id, other_wall.object_id)]


def test_ignore_static_collision_hides_static_pairs():
    with make_sim() as sim:  # ignore_static_collision defaults to True
        cube(sim, 0.0, mode=CollisionMode.STATIC)
        robot = cube(sim, 0.15)
        buddy = cube(sim, 0.3)
        pairs, _ = sim.check_collisions()
        assert pairs == [(robot.object_id, buddy.object_id)]


def test_normal_2d_ignores_height():
    with make_sim() as sim:
        low, high = (
            cube(sim, 0.0, z=0.1, mode="normal_2d"),
            cube(sim, 0.05, z=3.0, mode="normal_2d"),
        )
        flat_vs_3d = cube(sim, 5.0, z=0.1, mode="normal_2d"), cube(sim, 5.05, z=3.0)
        pairs, _ = sim.filter_aabb_pairs()
        assert (low.object_id, high.object_id) in pairs
        assert (flat_vs_3d[0].object_id, flat_vs_3d[1].object_id) in pairs  # one 2D side is enough
        three_d = cube(sim, 9.0, z=0.1), cube(sim, 9.05, z=3.0)
        pairs, _ = sim.filter_aabb_pairs()
        assert (three_d[0].object_id, three_d[1].object_id) not in pairs


def test_contact_points_with_physics():
    with make_sim(physics=True) as sim:
        assert sim.params.resolved_collision_detection_method.value == "contact_points"
        resting = cube(sim, 0.0, z=0.0)
        falling = cube(sim, 0.0, z=0.25, mass=1.0)
        apart = cube(sim, 3.0, z=0.0)
        started = []
        sim.events.on(
            SimEvents.COLLISION_STARTED, lambda **kw: started.append((kw["obj_a"], kw["obj_b"]))
        )
        for _ in range(10):
            sim.step_once()
        assert (resting, falling) in started
        assert all(apart not in pair for pair in started)


def test_events_fire_once_per_contact_and_count():
    with make_sim() as sim:
        a, b = cube(sim, 0.0), cube(sim, 1.0)
        log = []
        sim.events.on(
            SimEvents.COLLISION_STARTED, lambda **kw: log.append(("start", sim.step_count))
        )
        sim.events.on(SimEvents.COLLISION_ENDED, lambda **kw: log.append(("end", sim.step_count)))
        mine = []
        a.events.on(SimEvents.COLLISION_STARTED, lambda **kw: mine.append(kw["other"]))
        xs = [1.0, 0.6, 0.3, 0.19, 0.1, 0.05, 0.1, 0.3, 0.6, 0.15, 0.15]
        for x in xs:
            b.set_pose(Pose.from_xyz(x, 0.0, 0.5))
            sim.step_once()
        # touching (within 0.02 m of contact) from x=0.19 to x=0.1, apart at 0.3, again at 0.15
        assert log == [("start", 3), ("end", 7), ("start", 9)]
        assert sim.collision_count == 2 and mine == [b, b]
        assert sim.get_active_collision_pairs() == [(a.object_id, b.object_id)]


def test_a_collision_listener_hears_each_check_once_with_its_pairs():
    with make_sim() as sim:
        a, b, c = cube(sim, 0.0), cube(sim, 0.15), cube(sim, 3.0)
        heard = []

        def listener(ended, started):
            assert ended.dtype == started.dtype == np.int64
            heard.append(
                (
                    sim.step_count,
                    [tuple(pair) for pair in ended.tolist()],
                    [tuple(pair) for pair in started.tolist()],
                )
            )

        sim.add_collision_listener(listener)
        sim.step_once()
        c.set_pose(Pose.from_xyz(0.15, 0.15, 0.5))  # touches both
        sim.step_once()
        b_id = b.object_id
        sim.remove_object(b)
        sim.step_once()
        sim.step_once()  # nothing changes: no call
        assert sim.remove_collision_listener(listener)
        assert not sim.remove_collision_listener(listener)
        c.set_pose(Pose.from_xyz(5.0, 0.0, 0.5))
        sim.step_once()
        ab, ac, bc = (a.object_id, b_id), (a.object_id, c.object_id), (b_id, c.object_id)
        assert heard == [(0, [], [ab]), (1, [], [ac, bc]), (2, [ab, bc], [])]


def test_removing_an_object_ends_its_contacts():
    with make_sim() as sim:
        a, b = cube(sim, 0.0), cube(sim, 0.15)
        ended = []
        sim.events.on(SimEvents.COLLISION_ENDED, lambda **kw: ended.append(1))
        sim.step_once()
        assert sim.get_active_collision_pairs()
        sim.remove_object(b)
        sim.step_once()
        assert sim.get_active_collision_pairs() == [] and ended == [1]
        assert a.sim_core is sim


def test_check_frequency():
    with make_sim(collision_check_frequency=2.0) as sim:
        a, b = cube(sim, 0.0), cube(sim, 5.0)
        starts = []
        sim.events.on(SimEvents.COLLISION_STARTED, lambda **kw: starts.append(sim.step_count))
        b.set_pose(Pose.from_xyz(0.15, 0, 0.5))
        for _ in range(12):
            sim.step_once()
        assert starts == [0]  # checked at steps 0, 5, 10: the contact is seen at step 0
        sim.set_collision_check_frequency(0)
        b.set_pose(Pose.from_xyz(5.0, 0, 0.5))
        for _ in range(12):
            sim.step_once()
        assert sim.get_active_collision_pairs() == [(a.object_id, b.object_id)]  # never re-checked
        sim.set_collision_check_frequency(None)
        sim.step_once()
        assert sim.get_active_collision_pairs() == []
        with pytest.raises(ValueError, match="collision_check_frequency"):
            sim.set_collision_check_frequency(-1)


def test_static_wall_is_registered_once(sim):
    wall = SimObject.from_mesh(
        ShapeParams("box", half_extents=[5, 0.1, 1]),
        ShapeParams("box", half_extents=[5, 0.1, 1]),
        Pose.from_xyz(0, 0, 1),
        sim_core=sim,
        collision_mode="static",
    )
    robot = cube(sim, 0.0, y=2.0)
    sim.step_once()
    collision = sim._collision
    registered = collision.registrations
    for i in range(50):
        robot.set_pose(Pose.from_xyz(0.01 * i, 2.0, 0.5))
        sim.step_once()
    assert collision.registrations == registered == 2
    aabb_min, aabb_max = sim.get_aabbs()[wall.object_id]
    assert aabb_min == pytest.approx([-5, -0.1, 0]) and aabb_max == pytest.approx([5, 0.1, 2])


def test_rotated_aabb_is_tight():
    with make_sim() as sim:
        slab = SimObject.from_mesh(
            ShapeParams("box", half_extents=[1.0, 0.1, 0.1]),
            ShapeParams("box", half_extents=[1.0, 0.1, 0.1]),
            Pose.from_euler(0, 0, 0.5, yaw=np.pi / 2),
            sim_core=sim,
        )
        lo, hi = sim.get_aabbs()[slab.object_id]
        assert lo == pytest.approx([-0.1, -1.0, 0.4]) and hi == pytest.approx([0.1, 1.0, 0.6])
        pybullet_lo, pybullet_hi = p.getAABB(slab.body_id, physicsClientId=sim.client)
        assert np.all(np.array(lo) >= np.array(pybullet_lo) - 1e-6)
        assert np.all(np.array(hi) <= np.array(pybullet_hi) + 1e-6)


def test_collision_color_change_and_restore():
    with make_sim(enable_collision_color_change=True) as sim:
        a, b = cube(sim, 0.0), cube(sim, 3.0)
        original = p.getVisualShapeData(a.body_id, physicsClientId=sim.client)[0][7]
        b.set_pose(Pose.from_xyz(0.15, 0, 0.5))
        sim.step_once()
        assert p.getVisualShapeData(a.body_id, physicsClientId=sim.client)[0][7] == pytest.approx(
            sim.collision_color
        )
        b.set_pose(Pose.from_xyz(3.0, 0, 0.5))
        sim.step_once()
        assert p.getVisualShapeData(a.body_id, physicsClientId=sim.client)[0][7] == pytest.approx(
            original
        )


def test_profiling_and_cell_size_modes(sim):
    for i in range(10):
        cube(sim, 0.15 * i)
    pairs, timings = sim.check_collisions(return_profiling=True)
    assert len(pairs) == 9
    assert set(timings) >= {
        "get_aabbs",
        "spatial_hashing",
        "aabb_filtering",
        "contact_points",
        "total",
    }
    _, none = sim.filter_aabb_pairs()
    assert none is None
    assert (
        sim.set_collision_spatial_hash_cell_size_mode(
            SpatialHashCellSizeMode.CONSTANT, cell_size=3.0
        )
        == 3.0
    )
    assert sim.set_collision_spatial_hash_cell_size_mode(
        SpatialHashCellSizeMode.AUTO_ADAPTIVE
    ) == pytest.approx(0.6)
    with pytest.raises(ValueError, match="cell_size"):
        sim.set_collision_spatial_hash_cell_size_mode("constant", cell_size=-1)


def _brute_force(amin, amax, flat, moved):
    n = len(amin)
    out = []
    for i in range(n):
        for j in range(i + 1, n):
            if not (moved[i] or moved[j]):
                continue
            ignore_z = np.array([flat[i] or flat[j]])
            if aabb_overlap(
                amin[i : i + 1], amax[i : i + 1], amin[j : j + 1], amax[j : j + 1], ignore_z
            )[0]:
                out.append((i, j))
    return out


@pytest.mark.parametrize("seed", range(8))
def test_broad_phase_matches_brute_force_on_random_scenes(seed):
    rng = np.random.default_rng(seed)
    n = 300
    center = rng.uniform(-10, 10, (n, 3)) * [1, 1, 0.2]
    size = rng.uniform(0.05, 0.6, (n, 3))
    size[rng.random(n) < 0.03] *= 25  # a few huge objects span many cells
    amin, amax = center - size, center + size
    flat = rng.random(n) < 0.3
    moved = rng.random(n) < 0.5
    cell = float(rng.uniform(0.3, 2.0))
    idx = candidate_pairs(amin, amax, flat, moved, cell, 1.5)
    ignore_z = flat[idx[:, 0]] | flat[idx[:, 1]]
    kept = idx[
        aabb_overlap(amin[idx[:, 0]], amax[idx[:, 0]], amin[idx[:, 1]], amax[idx[:, 1]], ignore_z)
    ]
    assert [tuple(x) for x in kept.tolist()] == _brute_force(amin, amax, flat, moved)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("side_by_side", [False, True])
def test_broad_phase_two_cell_objects_match_brute_force(seed, side_by_side):
    # Objects smaller than a cell, many across a cell edge (at most two cells per axis): the
    # path that enters each object's 1-8 cells in one go; crowded, so cells hold 3+ entries.
    rng = np.random.default_rng(200 + seed)
    n = [40, 150, 400][seed % 3]  # up to _CORNER_MAX
    center = rng.uniform(-3, 3, (n, 3)) * [1, 1, 0.1]
    size = rng.uniform(0.02, 0.25, (n, 3))
    amin, amax = center - size, center + size
    flat = np.zeros(n, dtype=bool)
    moved = rng.random(n) < 0.5
    bounds = np.stack([amin, amax]) if side_by_side else None
    idx = candidate_pairs(amin, amax, None, moved, 0.6, 1.5, bounds)
    spans = np.floor(amax / 0.6) - np.floor(amin / 0.6)
    assert spans.max() == 1  # the scene exercises the two-cell path
    assert len(np.unique(idx, axis=0)) == len(idx)
    assert (idx[:, 0] < idx[:, 1]).all()
    kept = idx[
        aabb_overlap(
            amin[idx[:, 0]], amax[idx[:, 0]], amin[idx[:, 1]], amax[idx[:, 1]], flat[idx[:, 0]]
        )
    ]
    assert [tuple(x) for x in kept.tolist()] == _brute_force(amin, amax, flat, moved)


def test_simulated_scene_matches_brute_force_narrow_phase():
    rng = np.random.default_rng(7)
    with make_sim(collision_margin=0.02) as sim:
        objs = [cube(sim, *rng.uniform(-2, 2, 2), z=0.5) for _ in range(80)]
        pairs, _ = sim.check_collisions()
        expected = []
        for i, a in enumerate(objs):
            for b in objs[i + 1 :]:
                if p.getClosestPoints(a.body_id, b.body_id, 0.02, physicsClientId=sim.client):
                    expected.append((a.object_id, b.object_id))
        assert pairs == sorted(expected) and len(expected) > 5


def test_box_fast_path_matches_pybullet_with_sizes_offsets_and_rotations():
    # Unrotated single boxes take an exact numpy distance; rotated ones and spheres still go
    # to PyBullet. Either way the active pairs must equal PyBullet's own answer for every pair.
    rng = np.random.default_rng(3)
    with make_sim(collision_margin=0.03) as sim:
        objs = []
        for k in range(90):
            half = rng.uniform(0.05, 0.3, 3).tolist()
            shape = (
                ShapeParams("box", half_extents=half)
                if k % 9
                else ShapeParams("sphere", radius=0.15)
            )
            yaw = 0.0 if k % 4 else float(rng.uniform(0, np.pi))
            params = SimObjectSpawnParams(
                visual_shape=shape,
                collision_shape=shape,
                initial_pose=Pose.from_euler(*rng.uniform(-2, 2, 2), 0.5, yaw=yaw),
                collision_frame_pose=Pose([0.1, -0.05, 0.0]) if k % 5 == 0 else None,
            )
            objs.append(SimObject.from_params(params, sim))
        pairs, _ = sim.check_collisions()
        expected = []
        for i, a in enumerate(objs):
            for b in objs[i + 1 :]:
                if p.getClosestPoints(a.body_id, b.body_id, 0.03, physicsClientId=sim.client):
                    expected.append((a.object_id, b.object_id))
        assert pairs == sorted(expected) and len(expected) > 10


def _brute_force_pairs(amin, amax, flat, moved):
    """Every overlapping pair (i < j) with a moved side, by broadcasting (any n)."""
    out = []
    for i in range(len(amin) - 1):
        j = np.arange(i + 1, len(amin))
        sep = (amin[i] > amax[j]) | (amin[j] > amax[i])
        sep[:, 2] &= ~(flat[i] | flat[j])
        hit = j[~sep.any(axis=1) & (moved[i] | moved[j])]
        out += [(i, int(k)) for k in hit]
    return out


@pytest.mark.parametrize("seed", range(2))
def test_broad_phase_hash_table_path_matches_brute_force(seed):
    # Enough objects that equal cell keys are found with the hash table, not by sorting, and
    # crowded enough that many cells hold three or more objects.
    rng = np.random.default_rng(100 + seed)
    n = 3000
    center = rng.uniform(-5, 5, (n, 3)) * [1, 1, 0.05]
    size = rng.uniform(0.05, 0.3, (n, 3))
    size[rng.random(n) < 0.01] *= 15
    amin, amax = center - size, center + size
    flat = rng.random(n) < (0.25 if seed else 0.0)
    moved = rng.random(n) < 0.4
    idx = candidate_pairs(amin, amax, flat if flat.any() else None, moved, 0.6, 1.5)
    assert len(np.unique(idx, axis=0)) == len(idx)
    assert (idx[:, 0] < idx[:, 1]).all()
    ignore_z = flat[idx[:, 0]] | flat[idx[:, 1]]
    kept = idx[
        aabb_overlap(amin[idx[:, 0]], amax[idx[:, 0]], amin[idx[:, 1]], amax[idx[:, 1]], ignore_z)
    ]
    assert [tuple(x) for x in kept.tolist()] == _brute_force_pairs(amin, amax, flat, moved)


def test_one_cell_objects_and_a_quiet_check():
    # Objects far smaller than the cell (each in exactly one cell), then a check with nothing
    # moved: no work, the same active pairs, no events.
    with make_sim(spatial_hash_cell_size_mode="constant", spatial_hash_cell_size=5.0) as sim:
        objs = [cube(sim, 0.19 * i, y=0.5) for i in range(6)]
        started = []
        sim.events.on(SimEvents.COLLISION_STARTED, lambda obj_a, obj_b, **_: started.append(1))
        sim.step_once()
        pairs = sim.get_active_collision_pairs()
        assert pairs == [(objs[i].object_id, objs[i + 1].object_id) for i in range(5)]
        sim.step_once()
        assert sim.get_active_collision_pairs() == pairs and len(started) == 5


def _head_on(sweep, gap, lane=0.0, shape=None):
    """Two 0.1 m robots driving at each other at 2 m/s (dt 0.1 s); the collision events."""
    body = shape or ShapeParams("box", half_extents=[0.05, 0.05, 0.05])
    with make_sim(collision_sweep=sweep) as sim:
        ctrl = {"type": "omni", "max_linear_vel": 2.0}
        a = Agent.from_mesh(body, body, Pose.from_xyz(-gap, 0, 0.1), sim_core=sim, controller=ctrl)
        b = Agent.from_mesh(
            body, body, Pose.from_xyz(gap, lane, 0.1), sim_core=sim, controller=ctrl
        )
        a.set_goal_pose(Pose.from_xyz(gap + 3, 0, 0.1))
        b.set_goal_pose(Pose.from_xyz(-gap - 3, lane, 0.1))
        log = []
        for event in (SimEvents.COLLISION_STARTED, SimEvents.COLLISION_ENDED):
            sim.events.on(event, lambda e=event, **_: log.append((e, sim.step_count)))
        for _ in range(40):
            sim.step_once()
        return log


@pytest.mark.parametrize("gap", [0.9, 1.3])
def test_swept_check_reports_robots_that_pass_through_each_other_in_one_step(gap):
    # At 0.4 m per step of closing speed, neither end pose of the crossing step overlaps.
    assert _head_on(False, gap) == []
    started, ended = _head_on(True, gap)
    assert started[0] == SimEvents.COLLISION_STARTED and ended[0] == SimEvents.COLLISION_ENDED
    assert ended[1] == started[1] + 1  # reported by the crossing step, ended by the next one


def test_swept_check_keeps_near_misses_and_touches_apart():
    # Parallel lanes: faces pass 0.1 m apart (no contact), then 0.015 m apart (within the
    # 0.02 m margin: a contact whether or not the check is swept).
    assert _head_on(True, 0.9, lane=0.2) == []
    assert [e for e, _ in _head_on(True, 0.9, lane=0.115)] == [
        SimEvents.COLLISION_STARTED,
        SimEvents.COLLISION_ENDED,
    ]
    # A cube sweeping past another's edge with gaps of g on two axes comes within g * sqrt(2):
    # 0.014 m gaps (0.0198 m) are within the 0.02 m margin, 0.016 m gaps (0.0226 m) are not,
    # though each gap alone is (the swept test measures the distance, not the axes).
    for gap, expected in ((0.016, 0), (0.014, 1)):
        with make_sim(collision_sweep=True) as sim:
            cube(sim, 0.0)
            b = cube(sim, -5.0, y=0.2 + gap, z=0.7 + gap)
            sim.step_once()
            b.set_pose(Pose.from_xyz(5.0, 0.2 + gap, 0.7 + gap))
            sim.step_once()
            assert sim.collision_count == expected


def test_swept_check_of_other_shapes_uses_the_closest_approach():
    ball = ShapeParams("sphere", radius=0.05)
    assert _head_on(False, 0.9, shape=ball) == []
    assert [e for e, _ in _head_on(True, 0.9, shape=ball)] == [
        SimEvents.COLLISION_STARTED,
        SimEvents.COLLISION_ENDED,
    ]


def test_swept_box_distance_decision_matches_a_fine_scan():
    from fleet_async.core.collision.narrowphase import _within

    rng = np.random.default_rng(11)
    n = 120
    rel0, move = rng.uniform(-1, 1, (n, 3)), rng.uniform(-2, 2, (n, 3))
    half = rng.uniform(0.05, 0.3, (n, 3))
    t = np.linspace(0.0, 1.0, 10001)[:, None]
    least = np.array(
        [
            np.sqrt((np.maximum(np.abs(rel0[i] + t * move[i]) - half[i], 0) ** 2).sum(1)).min()
            for i in range(n)
        ]
    )
    for margin in (0.02, 0.1, 0.3):
        clear = np.abs(least - margin) > 3e-4  # rows the scan itself resolves
        assert (_within(rel0, move, half, margin) == (least <= margin))[clear].all()


def test_reading_aabbs_between_a_removal_and_the_check_still_ends_its_contacts():
    # A camera (recorder, GUI) reads the AABBs after every frame: that must not swallow the
    # news that an object left, for the next check or for idle_steps.
    with make_sim() as sim:
        a, b = cube(sim, 0.0), cube(sim, 0.15)
        sim.step_once()
        assert sim.get_active_collision_pairs() == [(a.object_id, b.object_id)]
        ended = []
        sim.events.on(SimEvents.COLLISION_ENDED, lambda obj_a, obj_b, **_: ended.append(1))
        sim.remove_object(b)
        assert sim.get_aabb_bounds() is not None  # what a camera does
        assert sim.idle_steps(5) == 0  # a check has news
        sim.step_once()
        assert sim.get_active_collision_pairs() == [] and ended == [1]
        assert sim.idle_steps(5) == 5


def _few_movers_log(sim, n_movers):
    """Collision events of a dense grid where a few robots drive through the others."""
    from fleet_async import Agent as _Agent
    from fleet_async import SimEvents as _Events

    log = []
    sim.events.on(
        _Events.COLLISION_STARTED,
        lambda obj_a, obj_b, **_: log.append(
            ("+", sim.step_count, obj_a.object_id, obj_b.object_id)
        ),
    )
    sim.events.on(
        _Events.COLLISION_ENDED,
        lambda obj_a, obj_b, **_: log.append(
            ("-", sim.step_count, obj_a.object_id, obj_b.object_id)
        ),
    )
    cube = ShapeParams("box", half_extents=[0.2, 0.2, 0.2])
    agents = [
        _Agent.from_mesh(
            cube,
            cube,
            Pose.from_xyz(0.5 * (i % 12), 0.5 * (i // 12), 0.2),
            sim_core=sim,
            controller="omni",
            collision_mode="normal_2d" if i % 5 == 0 else "normal_3d",
        )
        for i in range(144)
    ]
    for k in range(n_movers):
        agents[13 * k + 3].set_goal_pose(Pose.from_xyz(6.5 - k, 0.3 * k, 0.2))
    for _ in range(60):
        sim.step_once()
    return log


def test_few_movers_find_what_the_hash_finds(monkeypatch):
    def logs():
        out = []
        for movers in (1, 3):
            sim = MultiRobotSimulationCore(headless_params())
            try:
                out.append(_few_movers_log(sim, movers))
            finally:
                sim.close()
        return out

    monkeypatch.setattr("fleet_async.core.collision.broadphase._FEW_MIN_ROWS", 0)
    few = logs()
    monkeypatch.setattr("fleet_async.core.collision.broadphase._FEW_MOVERS", 0)  # always hash
    assert few == logs()
    assert len(few[0]) > 4 and len(few[1]) > len(few[0])
