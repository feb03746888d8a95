"""The floor of a numpy step: the cost of the numpy calls a step of the bare fleet workload
cannot avoid, measured on the workload's own arrays.

A step moves the moving robots along their segments and checks collisions. Done with numpy,
whatever the code around it, that takes at least these passes over arrays (one call each;
K = moving robots, N = all, P = candidate pairs, C = pairs touching):

- motion (K): gather the movers' segment columns (1); count the step and its time (2);
  sample the trapezoid (rising, cruise and braking terms, two selects, the clip: 10); the
  arrival test (1); position on the segment (2); read the old positions, difference, divide
  by dt (3); write positions and velocities (2); flag the rows moved (1): 22 calls;
- AABBs (N): add the body-frame corners to the positions (1);
- broad phase (N): cell coordinates (floor, cast: 2), spans (1), keys (1), order the keys
  (1 argsort: a hash table needs more calls), equal neighbours (2), the pairs and their moved
  flags (3): 10 calls;
- narrow phase (P): gather positions, centres, half extents (3), gap, clip, square, sum,
  sqrt, compare with the margin (6): 9 calls;
- active pairs (C): pair codes (3), sort (1), membership of old and new (2): 6 calls;
- clear the moved flags (1).

That is 49 numpy calls; the numpy step makes about 80 and the compiled step 2 kernels and
about 25 numpy calls. The floor is timed as the median CPU time of 200 repetitions of those
calls (each run on arrays of the sizes a timed step of the workload has), plus the cost of a
step in which nothing moves (the step loop's own Python: phases, clock, events).

Run:  python benchmarks/step_floor.py [--n 100 1000 10000 100000]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np

from fleet_async import bench
from fleet_async.core.simulation import MultiRobotSimulationCore


def _median_cpu_us(fn: Callable[[], object], reps: int) -> float:
    times = []
    for _ in range(reps):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return statistics.median(times) * 1e6


def _state(n: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Positions and moved flags of the workload at its first timed step, and the idle
    step's cost in us (the same fleet once nothing moves)."""
    with MultiRobotSimulationCore(bench.bench_params()) as sim:
        agents = bench.spawn_fleet(sim, n)
        bench.set_goals(agents, n)
        for _ in range(bench.WARMUP_STEPS):
            sim.step_once()
        state = sim.state
        position = state.position[:n].copy()
        moved = np.array([a.is_moving for a in agents])
        for agent in agents:
            agent.stop()
        sim.step_once()
        idle = _median_cpu_us(sim.step_once, 200)
    return position, moved, idle


def floor_us(n: int, reps: int = 200) -> dict[str, float]:
    """Median CPU us of the unavoidable numpy passes of one step at ``n`` robots."""
    position, moved, idle = _state(n)
    rng = np.random.default_rng(0)
    rows = moved.nonzero()[0]
    k = len(rows)
    flat = rows * 3 + np.arange(3)[:, None]
    block = rng.random((20, 2 * n))  # the movers' segment columns live in a wider matrix
    slots = rows.copy()
    vel = np.zeros_like(position)
    offsets = np.stack([np.full((n, 3), -0.06), np.full((n, 3), 0.06)])
    aabb = np.empty_like(offsets)
    weights = np.array([1 << 42, 1 << 21, 1], dtype=np.int64)
    flags = moved.copy()
    dt, inv = 0.1, 1.0 / 0.3

    def motion() -> None:
        f = block.take(slots, axis=1)
        steps = f[0] + 1.0
        t = steps * dt
        rising = f[1] * t * t / f[2]  # 3 calls
        cruise = f[3] * (t - f[4])  # 2
        braking = 1.0 - f[1] * f[5] * f[5]  # 3 (the left time stands in f[5])
        u = np.where(t < f[6], rising, np.where(t > f[7], braking, cruise))  # 4 with compares
        np.minimum(u, 1.0, out=u)
        arrived = t >= f[8]  # noqa: F841  (the arrival test is part of the work)
        pos = f[9:12] + f[12:15] * u  # 2
        p = position.reshape(-1)
        vel.reshape(-1)[flat] = (pos - p[flat]) / dt  # 4 (gather, subtract, divide, write)
        p[flat] = pos
        flags[rows] = True

    def collision() -> tuple[np.ndarray, np.ndarray]:
        np.add(position, offsets, out=aabb)
        cells = np.floor(aabb * inv).astype(np.int64)
        span = cells[1] - cells[0]
        keys = cells[0] @ weights
        order = keys.argsort()
        ks = keys[order]
        first = (ks[1:] == ks[:-1]).nonzero()[0]
        pairs = order[first[:, None] + np.arange(2)]
        keep = flags[pairs]
        pairs = pairs.compress(keep[:, 0] | keep[:, 1], axis=0)
        return pairs, span

    pairs, _ = collision()
    half = np.full((n, 3), 0.05)

    def narrow() -> np.ndarray:
        p = position.take(pairs, axis=0)
        c = p + half.take(pairs, axis=0) * 0.0  # centres: one gather and one add
        h = half.take(pairs, axis=0)
        gap = np.abs(c[:, 0] - c[:, 1]) - h[:, 0] - h[:, 1]
        np.maximum(gap, 0.0, out=gap)
        gap *= gap
        return np.sqrt(gap.sum(axis=1)) <= 0.02

    touching = narrow()
    active = np.sort(rng.integers(0, n * n, max(1, len(pairs))))

    def pairs_update() -> None:
        t = pairs.compress(touching, axis=0)
        codes = (np.minimum(t[:, 0], t[:, 1]) << 32) | np.maximum(t[:, 0], t[:, 1])
        codes.sort()
        np.searchsorted(active, codes)
        np.searchsorted(codes, active)
        flags[:] = False

    parts = {
        "motion": _median_cpu_us(motion, reps),
        "collision (AABB, broad phase)": _median_cpu_us(collision, reps),
        "narrow phase": _median_cpu_us(narrow, reps),
        "active pairs, flags": _median_cpu_us(pairs_update, reps),
        "idle step (Python only)": idle,
    }
    parts["floor"] = sum(parts.values())
    parts["movers"] = k
    parts["candidate pairs"] = len(pairs)
    return parts


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[100, 1000, 10000, 100000])
    args = parser.parse_args()
    for n in args.n:
        parts = floor_us(n)
        text = ", ".join(f"{key} {value:.1f}" for key, value in parts.items())
        print(f"N={n}: {text} (CPU us, medians)", flush=True)


if __name__ == "__main__":
    main()
