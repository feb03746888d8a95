"""Collision benchmark: broad-phase and narrow-phase time for 1,000 and 10,000 moving boxes.

Boxes (0.1 m cubes) sit on a 1 m grid with small random offsets; every step each box moves a
little, so every box is "moved" for the collision system and the broad phase sees all of them.

Run:  python benchmarks/collision_bench.py [--n 1000 10000] [--steps 50]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from fleet_async import (
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimObject,
    SimObjectSpawnParams,
    SimulationParams,
)


def run(n: int, steps: int) -> dict[str, float]:
    """Mean ms per check for each collision stage with N moving boxes."""
    params = SimulationParams(
        gui=False, monitor=False, target_rtf=0.0, enable_floor=False, collision_check_frequency=0
    )
    rng = np.random.default_rng(0)
    side = math.ceil(math.sqrt(n))
    cube = ShapeParams("box", half_extents=[0.05, 0.05, 0.05])
    with MultiRobotSimulationCore(params) as sim:
        objs = SimObject.spawn_batch(
            [
                SimObjectSpawnParams(
                    visual_shape=cube,
                    collision_shape=cube,
                    initial_pose=Pose.from_xyz(i % side, i // side, 0.1),
                )
                for i in range(n)
            ],
            sim,
        )
        ids = [o.object_id for o in objs]
        base = np.array([[i % side, i // side, 0.1] for i in range(n)], dtype=float)
        orientations = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        sim.check_collisions()  # registration happens once, on first sight
        totals: dict[str, float] = {}
        for _ in range(steps):
            jitter = rng.uniform(-0.48, 0.48, size=(n, 3)) * [1, 1, 0]
            sim.set_poses(ids, base + jitter, orientations)
            _, timings = sim.check_collisions(return_profiling=True)
            for key, value in (timings or {}).items():
                totals[key] = totals.get(key, 0.0) + value / steps
        totals["active_pairs"] = float(len(sim.get_active_collision_pairs()))
    return totals


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--steps", type=int, default=50)
    args = parser.parse_args(argv)
    for n in args.n:
        t = run(n, args.steps)
        broad = t["get_aabbs"] + t["spatial_hashing"] + t["aabb_filtering"]
        print(
            f"N={n:>6}: broad phase {broad:7.3f} ms (aabbs {t['get_aabbs']:.3f}, "
            f"hash {t['spatial_hashing']:.3f}, filter {t['aabb_filtering']:.3f})  "
            f"narrow phase {t['contact_points']:7.3f} ms  total {t['total']:7.3f} ms  "
            f"active pairs {int(t['active_pairs'])}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
