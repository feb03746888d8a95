"""The compiled kernels (numba, ``SimulationParams.kernels``) against the numpy code: the same
seeded workloads run on both paths and every pose, velocity and collision pair must be equal
bit for bit, step by step; and the switch says clearly what it needs when numba is missing."""

from __future__ import annotations

import math

import numba  # the test extra installs it (fleet-async[fast]): these tests never skip
import numpy as np
import pytest

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    Path,
    Pose,
    ShapeParams,
    SimObject,
)
from fleet_async.core.agents import batteries
from fleet_async.core.agents.batteries import BatteryBank
from fleet_async.core.base import compiled
from fleet_async.core.base.params import SimulationParams
from fleet_async.core.collision import safety_geometry
from fleet_async.core.collision.broadphase import candidate_pairs
from fleet_async.core.collision.check_jit import SharedCellPairs, field_pair_hits
from fleet_async.core.world.state import KinematicState
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.05, 0.05, 0.05])
STEPS = 120


def _fleet(
    kernels: str, n: int, seed: int, flat: bool = False, sweep: bool = False
) -> MultiRobotSimulationCore:
    """n boxes on a 1 m grid, omni and differential, with seeded goals, paths and headings;
    with ``flat`` a third are NORMAL_2D and a static wall stands among them; ``sweep``: swept
    collision checks."""
    sim = MultiRobotSimulationCore(
        headless_params(
            kernels=kernels, collision_margin=0.02, enable_floor=False, collision_sweep=sweep
        )
    )
    rng = np.random.default_rng(seed)
    side = math.ceil(math.sqrt(n))
    params = []
    for i in range(n):
        kind = "differential" if i % 3 == 0 else "omni"
        params.append(
            AgentSpawnParams(
                visual_shape=BOX,
                collision_shape=BOX,
                initial_pose=Pose.from_euler(i % side, i // side, 0.1, yaw=rng.uniform(-3, 3)),
                mass=0.0,
                controller={"type": kind, "max_linear_vel": 2.0, "max_angular_vel": 3.0},
                collision_mode="normal_2d" if flat and i % 3 == 1 else "normal_3d",
            )
        )
    agents = Agent.spawn_batch(params, sim)
    if flat:
        wall = ShapeParams("box", half_extents=[side / 2, 0.05, 0.5])
        SimObject.from_mesh(wall, wall, Pose.from_xyz(side / 2, side / 2 - 0.5, 0.5), sim_core=sim)
    for agent in agents:
        roll = rng.random()
        if roll < 0.4:
            x, y = rng.uniform(-5, side + 5, 2)
            agent.set_goal_pose(Pose.from_euler(x, y, 0.1, yaw=rng.uniform(-3, 3)))
        elif roll < 0.7:
            points = rng.uniform(-3, side + 3, (3, 2))
            agent.set_path(
                Path([Pose.from_euler(px, py, 0.1, yaw=rng.uniform(-3, 3)) for px, py in points])
            )
    return sim


def _trace(sim: MultiRobotSimulationCore, steps: int) -> list[tuple[object, ...]]:
    out = []
    state = sim.state
    for _ in range(steps):
        sim.step_once()
        high = state.high_water
        out.append(
            (
                *(
                    getattr(state, name)[:high].copy().view(np.int64)  # bits, not values
                    for name in ("position", "orientation", "velocity", "angular_velocity")
                ),
                tuple(sim.get_active_collision_pairs()),
                sim.collision_count,
            )
        )
    sim.close()
    return out


def _assert_same(a: list[tuple[object, ...]], b: list[tuple[object, ...]]) -> None:
    assert len(a) == len(b)
    for step, (x, y) in enumerate(zip(a, b, strict=True)):
        for name, u, v in zip(("pos", "orn", "vel", "ang", "pairs", "count"), x, y, strict=True):
            same = np.array_equal(u, v) if isinstance(u, np.ndarray) else u == v
            assert same, f"step {step}: {name} differs"


@pytest.mark.parametrize(("n", "seed"), [(150, 1), (700, 2)])
def test_numba_and_numpy_give_the_same_bits_step_by_step(n, seed):
    numpy_run = _trace(_fleet("numpy", n, seed), STEPS)
    numba_run = _trace(_fleet("numba", n, seed), STEPS)
    _assert_same(numpy_run, numba_run)
    # the workload did what it is for: robots moved, turned, arrived and collided
    first, last = numpy_run[0], numpy_run[-1]
    assert not np.array_equal(first[0], last[0]) and not np.array_equal(first[1], last[1])
    assert last[5] > 0


def test_flat_objects_and_a_static_wall_hand_over_to_numpy_with_the_same_result():
    _assert_same(
        _trace(_fleet("numpy", 200, 3, flat=True), 60), _trace(_fleet("numba", 200, 3, True), 60)
    )


def test_swept_checks_give_the_same_bits():
    _assert_same(
        _trace(_fleet("numpy", 150, 4, sweep=True), 60),
        _trace(_fleet("numba", 150, 4, sweep=True), 60),
    )


def _boxes(rng: np.random.Generator, n: int, spread: float, size: float) -> np.ndarray:
    centre = rng.uniform(-spread, spread, (n, 3))
    centre[:, 2] = rng.uniform(0, 0.5, n)
    half = rng.uniform(0.2, 1.0, (n, 1)) * size
    return np.stack([centre - half, centre + half])


@pytest.mark.parametrize(
    ("n", "spread", "size", "share_moved"),
    [(50, 3.0, 0.3, 0.5), (500, 10.0, 0.2, 0.3), (3000, 20.0, 0.15, 1.0), (800, 2.0, 0.3, 0.1)],
)
def test_the_broad_phase_kernel_finds_the_numpy_pairs(n, spread, size, share_moved):
    rng = np.random.default_rng(n)
    kernel = SharedCellPairs()
    for _ in range(3):  # the kernel's buffers are reused (and grown) between calls
        bounds = _boxes(rng, n, spread, size)
        moved = rng.random(n) < share_moved
        expected = candidate_pairs(bounds[0], bounds[1], None, moved, 0.3, 1.5, bounds)
        found = candidate_pairs(bounds[0], bounds[1], None, moved, 0.3, 1.5, bounds, kernel)
        assert len(expected) > 0
        assert found.dtype == np.int64 and np.array_equal(found, expected)


def test_the_broad_phase_kernel_hands_big_objects_and_far_cells_to_numpy():
    kernel = SharedCellPairs()
    bounds = _boxes(np.random.default_rng(0), 40, 2.0, 0.3)
    moved = np.ones(40, dtype=bool)
    bounds[1, 0] += 5.0  # one object spans many 1 m cells
    assert kernel(bounds[0], bounds[1], moved, 1.0, 1.5)[1] is False
    bounds = _boxes(np.random.default_rng(0), 40, 2.0, 0.3)
    bounds[:, 1] += 2.0**21  # cells 2**21 apart: the numpy code's keys may alias
    assert kernel(bounds[0], bounds[1], moved, 1.0, 1.5)[1] is False
    bounds = _boxes(np.random.default_rng(0), 40, 2.0, 0.3)
    pairs, done = kernel(bounds[0], bounds[1], moved, 1.0, 1.5)
    assert done is True and len(pairs) > 0


def test_kernels_numba_fails_clearly_without_numba(monkeypatch):
    monkeypatch.setattr(compiled, "_available", False)
    monkeypatch.setattr(compiled, "_reason", "ModuleNotFoundError: No module named 'numba'")
    with pytest.raises(ImportError, match=r"kernels='numba'.*fleet-async\[fast\]"):
        MultiRobotSimulationCore(headless_params(kernels="numba"))
    assert compiled.use_numba("auto") is False  # auto falls back to numpy quietly
    with MultiRobotSimulationCore(headless_params(kernels="auto")) as sim:
        agent = Agent.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim)
        agent.set_goal_pose(Pose.from_xyz(1.0, 0.0, 0.1))
        for _ in range(20):
            sim.step_once()
        assert agent.get_pose().position.tolist() == [1.0, 0.0, 0.1]


def test_kernels_is_checked():
    with pytest.raises(ValueError, match=r"SimulationParams\.kernels: expected one of"):
        SimulationParams(kernels="fortran")
    with pytest.raises(ValueError, match="'fortran'"):
        compiled.use_numba("fortran")
    assert compiled.use_numba("numpy") is False
    assert compiled.use_numba("numba") is True and numba.__version__


@pytest.mark.parametrize("seed", [0, 1])
def test_the_safety_fields_pair_test_kernel_matches_numpy(seed):
    """check_jit.field_pair_hits against safety_geometry.pair_hits on seeded fields and boxes
    (turned fields, boxes touching on a grid of 0.25 m, some out of the z band, a NaN box)."""
    rng = np.random.default_rng(seed)
    m, k, p = 60, 80, 4000
    travel = rng.normal(size=(m, 2))
    travel /= np.hypot(travel[:, 0], travel[:, 1])[:, None]
    heading = rng.normal(size=(m, 2))
    heading /= np.hypot(heading[:, 0], heading[:, 1])[:, None]
    shapes = safety_geometry.FieldShapes(
        tuple(np.round(rng.uniform(0, 6, (2, m)) * 4) / 4),
        (heading[:, 0], heading[:, 1]),
        (travel[:, 0], travel[:, 1]),
        rng.uniform(0.1, 0.5, m),
        rng.uniform(0.1, 0.4, m),
        rng.uniform(0.0, 0.2, m),
    )
    prot = rng.uniform(0.0, 1.0, m)
    warn = prot + rng.uniform(0.0, 1.0, m)
    fields = safety_geometry.field_columns(
        shapes, warn, prot, rng.uniform(0.0, 0.3, m), rng.uniform(0.5, 1.0, m)
    )
    lo = np.round(rng.uniform(-1, 6, (k, 3)) * 4) / 4
    lo[:, 2] = rng.uniform(-0.5, 1.2, k)
    hi = lo + np.round(rng.uniform(0, 1.5, (k, 3)) * 4) / 4
    lo[0] = np.nan
    boxes = safety_geometry.box_columns(lo, hi)
    field, box = rng.integers(0, m, p), rng.integers(0, k, p)
    hit, in_prot = safety_geometry.pair_hits(fields, boxes, field, box)
    hit_jit, in_prot_jit = field_pair_hits(fields, boxes, field, box)
    assert 50 < len(hit) < p // 2  # the pairs mix hits and misses, protective and not
    assert 0 < np.count_nonzero(in_prot) < len(hit)
    assert np.array_equal(hit_jit, hit)
    assert np.array_equal(in_prot_jit, in_prot)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_battery_kernel_matches_the_numpy_pass(seed):
    """batteries_jit.drive_batteries against BatteryBank.drive's numpy pass on the same seeded
    batteries and velocities, step by step: charging and not, standing spans between drives,
    charges at the bounds (0 and 1), a spin without a velocity, a NaN velocity."""
    rng = np.random.default_rng(seed)
    n = 300
    store = KinematicState(capacity=n)
    rows = store.allocate_many(
        np.arange(n), np.full(n, -1), np.zeros((n, 3)), np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    )
    banks = [BatteryBank(lambda: 0, 0.1, store, capacity=8, compiled=c) for c in (False, True)]
    for i in range(n):
        values = {name: float(rng.uniform(0.0, 0.02)) for name in batteries.FIELDS}
        values["soc0"] = float(rng.choice([0.0, 1.0, rng.uniform(0.0, 1.0)]))
        values["used0"] = values["distance"] = 0.0
        for bank in banks:
            bank.add(dict(values), 0, bool(i % 3 == 0), int(rows[i]), True)
    moved_any = []
    for step in range(40):
        velocity = rng.normal(size=(n, 3)) * (rng.random((n, 1)) < 0.6)
        spin = np.zeros((n, 3))
        spin[rng.random(n) < 0.05, 2] = 0.5
        if step == 7:
            velocity[5] = np.nan
        store.velocity[:n], store.angular_velocity[:n] = velocity, spin
        if step % 9 == 0:  # a standing step for everyone: nothing is applied
            store.velocity[:n] = 0.0
            store.angular_velocity[:n] = 0.0
        results = [bank.drive(step) for bank in banks]
        assert results[0] == results[1]
        moved_any.append(results[0])
        for name in batteries.FIELDS:
            assert banks[0].values[name].tobytes() == banks[1].values[name].tobytes(), name
        assert banks[0].step0.tobytes() == banks[1].step0.tobytes()
    assert any(moved_any) and not all(moved_any)
    soc = banks[0].values["soc0"][:n]
    assert (soc == 0.0).any() and np.isnan(soc).any()
