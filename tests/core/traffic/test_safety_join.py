"""The safety fields' fast evaluation (a pair list kept between steps) against the reference
(the generic broad phase every step): same stops, same events, same poses, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
)
from fleet_async.core.collision.safety_geometry import field_columns
from fleet_async.core.collision.safety_join import box_pairs
from fleet_async.core.collision.safety_state import FieldTable
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.2])
CRATE = ShapeParams("box", half_extents=[0.25, 0.25, 0.3])


def crowd(evaluator: str, seed: int, robots: int = 120, steps: int = 150, kernels="numpy"):
    """A seeded crowd: robots (both motion modes, random headings) driving random paths
    among each other, crates and a map's boxes; returns (events, poses per step, stats)."""
    sim = MultiRobotSimulationCore(headless_params(enable_floor=True, seed=seed, kernels=kernels))
    sim.safety.evaluator = evaluator
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(robots)))
    params = []
    for i in range(robots):
        x = 1.3 * (i % side) + rng.uniform(-0.2, 0.2)
        y = 1.3 * (i // side) + rng.uniform(-0.2, 0.2)
        params.append(
            AgentSpawnParams(
                visual_shape=None,
                collision_shape=BOX,
                initial_pose=Pose.from_euler(x, y, 0.2, 0.0, 0.0, rng.uniform(-3.0, 3.0)),
                motion_mode="omnidirectional" if i % 3 else "differential",
                safety_field={"warning_margin": float(rng.uniform(0.0, 1.0))},
            )
        )
    agents = Agent.spawn_batch(params, sim)
    for _ in range(5):
        SimObject.from_mesh(
            CRATE, CRATE, Pose.from_xyz(*rng.uniform(0, 1.3 * side, 2), 0.3), sim_core=sim
        )
    lo = np.array([[-1.0, -1.0, 0.0], [1.3 * side, -1.0, 0.0]])
    hi = np.array([[1.3 * side, -0.5, 1.0], [1.3 * side + 0.5, 1.3 * side, 1.0]])
    sim.safety.add_static_boxes(lo, hi)
    for agent in agents:
        x, y, z = agent.get_pose().position.tolist()
        goals = rng.uniform(-6.0, 6.0, (3, 2)) + np.array([x, y])
        agent.set_path([Pose.from_xyz(gx, gy, z) for gx, gy in goals.tolist()])
    log: list[tuple] = []

    def on(kind):
        def handler(agent, **data):
            obstacles = tuple(o.object_id for o in data.get("obstacles", ()))
            log.append((kind, sim.step_count, agent.object_id, obstacles, data.get("duration")))

        return handler

    sim.events.on(SimEvents.SAFETY_STOP_STARTED, on("start"))
    sim.events.on(SimEvents.SAFETY_STOP_ENDED, on("end"))
    poses = []
    for step in range(steps):
        if step == steps // 2:  # an agent leaves, one loses its fields: the list is rebuilt
            sim.remove_object(agents[0])
            sim.safety.disable(agents[1])
        sim.step_once()
        store = sim.world.store
        poses.append(store.position[: store.high_water].copy())
    stats = sim.safety.stats()
    sim.close()
    return log, poses, stats


@pytest.mark.parametrize(
    ("seed", "kernels"), [(0, "numpy"), (1, "numpy"), (2, "numpy"), (0, "numba"), (3, "numba")]
)
def test_fast_fields_match_the_reference_bit_for_bit(seed, kernels):
    ref_log, ref_poses, ref_stats = crowd("reference", seed)
    log, poses, stats = crowd("pairs", seed, kernels=kernels)
    assert len(ref_log) > 20  # the crowd stops robots: the comparison means something
    assert log == ref_log
    assert stats == ref_stats
    assert len(poses) == len(ref_poses)
    for step, (a, b) in enumerate(zip(poses, ref_poses, strict=True)):
        assert np.array_equal(a, b), f"poses differ at step {step + 1}"


def test_compiled_field_frames_match_the_numpy_shapes_bit_for_bit(monkeypatch):
    """Step by step, the kernels' shapes, depths, active flags, field columns and warning
    bounds equal what the numpy code computes from the same state."""
    seen: list[tuple[np.ndarray, ...]] = []
    compiled = FieldTable._shapes_compiled

    def checked(table, on_path, segments):
        shapes, active = compiled(table, on_path, segments)
        fields, lo, hi = table.frame
        depths = (table.speed, table.protective_depth, table.warning_depth)
        kernels, table.kernels = table.kernels, None
        try:  # the numpy code on the same state (its memo only caches the same values)
            ref, ref_active = FieldTable.shapes(table, on_path, segments)
        finally:
            table.kernels = kernels
        ref_depths = (table.speed, table.protective_depth, table.warning_depth)
        z_lo, z_hi = table.z_band(np.arange(len(table.rows)))
        warn, prot = ref_depths[2], ref_depths[1]
        ref_fields = field_columns(ref, warn, prot, z_lo, z_hi)
        f_lo, f_hi = ref.bounds(warn)
        names = ("cx", "cy", "ux", "uy", "wx", "wy", "ext_u", "half_w")
        for name in names:
            assert getattr(shapes, name).tobytes() == getattr(ref, name).tobytes(), name
        assert active.tobytes() == ref_active.tobytes()
        for got, want in zip(depths, ref_depths, strict=True):
            assert got.tobytes() == want.tobytes()
        assert fields.tobytes() == ref_fields.tobytes()
        assert lo.tobytes() == np.column_stack((f_lo, z_lo)).tobytes()
        assert hi.tobytes() == np.column_stack((f_hi, z_hi)).tobytes()
        table.speed, table.protective_depth, table.warning_depth = depths
        table._shapes, table._active, table.frame = shapes, active, (fields, lo, hi)
        seen.append(active)
        return shapes, active

    monkeypatch.setattr(FieldTable, "_shapes_compiled", checked)
    crowd("pairs", 4, robots=60, steps=80, kernels="numba")
    assert len(seen) >= 75 and any(not a.all() for a in seen) and any(a.any() for a in seen)


def test_an_unknown_evaluator_is_refused():
    with MultiRobotSimulationCore(headless_params()) as sim:
        with pytest.raises(ValueError, match="'fast'"):
            sim.safety.evaluator = "fast"
        assert sim.safety.evaluator == "pairs"


def brute_pairs(q_lo, q_hi, t_lo, t_hi):
    ok = np.all(q_lo[:, None, :] <= t_hi[None, :, :], axis=2)
    ok &= np.all(t_lo[None, :, :] <= q_hi[:, None, :], axis=2)
    return {tuple(p) for p in np.argwhere(ok).tolist()}


boxes = st.lists(
    st.tuples(
        st.floats(-20, 20), st.floats(-20, 20), st.floats(0, 6), st.floats(0, 6), st.floats(0, 2)
    ),
    max_size=40,
)


def as_boxes(items):
    a = np.array(items, dtype=float).reshape(-1, 5)
    lo = np.column_stack((a[:, 0], a[:, 1], np.zeros(len(a))))
    hi = np.column_stack((a[:, 0] + a[:, 2], a[:, 1] + a[:, 3], a[:, 4]))
    return lo, hi


@settings(max_examples=150, deadline=None)
@given(queries=boxes, targets=boxes, cell=st.sampled_from([0.3, 1.0, 2.5]))
def test_box_pairs_finds_every_overlapping_pair_once(queries, targets, cell):
    q_lo, q_hi = as_boxes(queries)
    t_lo, t_hi = as_boxes(targets)
    qi, ti = box_pairs(q_lo, q_hi, t_lo, t_hi, cell)
    found = list(zip(qi.tolist(), ti.tolist(), strict=True))
    assert len(found) == len(set(found))  # each pair once
    assert set(found) == brute_pairs(q_lo, q_hi, t_lo, t_hi)


def test_box_pairs_pairs_a_huge_box_with_everything_it_meets():
    q_lo = np.array([[0.0, 0.0, 0.0], [50.0, 50.0, 0.0], [0.0, 0.0, 5.0]])
    q_hi = q_lo + np.ones(3)
    t_lo = np.array([[-1e6, -1e6, -1.0], [0.5, 0.5, 0.0]])
    t_hi = np.array([[1e6, 1e6, 0.5], [0.7, 0.7, 0.2]])
    qi, ti = box_pairs(q_lo, q_hi, t_lo, t_hi, 1.0)
    assert sorted(zip(qi.tolist(), ti.tolist(), strict=True)) == [(0, 0), (0, 1), (1, 0)]
