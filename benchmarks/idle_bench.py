"""Idle steps: what an empty step costs, and what skipping empty spans buys a sparse model.

1. ``empty``: a step in which nothing moves and nothing is due (N idle agents, collision checks
   every step), timed with ``timeit`` (best of 7 rounds), and ``sim.idle_steps(1000)``.
2. ``sparse``: a sparse model: N agents, each sent 2 m away every 60 s of sim time by a 1 Hz
   callback (so most steps are empty), run for ``--hours`` of sim time at dt 0.1 s, once with
   ``step_once()`` only and once with ``run_simulation`` (which skips empty spans); both must
   end in the same state (the benchmark checks it).

Run:  python benchmarks/idle_bench.py [--n 0 100 10000] [--agents 20] [--hours 1.0]
"""

from __future__ import annotations

import argparse
import math
import time
import timeit

from fleet_async import bench
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.simulation import MultiRobotSimulationCore


def empty_step_us(n: int) -> tuple[float, float]:
    """(us per empty step, us per idle_steps(1000)) with N idle agents."""
    with MultiRobotSimulationCore(bench.bench_params()) as sim:
        if n:
            bench.spawn_fleet(sim, n)
        for _ in range(3):
            sim.step_once()
        step = min(timeit.repeat(sim.step_once, number=2000, repeat=7)) / 2000
        idle = min(timeit.repeat(lambda: sim.idle_steps(1000), number=2000, repeat=7)) / 2000
        return step * 1e6, idle * 1e6


def sparse_run(n: int, hours: float, skip: bool) -> tuple[float, int, list[list[float]]]:
    """Wall seconds, steps and final positions of the sparse model."""
    with MultiRobotSimulationCore(bench.bench_params()) as sim:
        agents = bench.spawn_fleet(sim, n)
        for agent in agents:
            agent.register_callback(lambda obj, dt: None, 1 / 3600.0)  # a rare per-object one

        def dispatch(s: MultiRobotSimulationCore, dt: float) -> None:
            k = round(s.sim_time)
            if k % 60 == 0:
                agent = agents[(k // 60) % n]
                pose = agent.get_pose()
                agent.set_goal_pose(Pose.from_xyz(pose.x, pose.y + 2.0, pose.z))

        sim.register_callback(dispatch, frequency=1.0)
        steps = math.ceil(hours * 3600 / bench.TIMESTEP - 1e-9)
        t0 = time.perf_counter()
        if skip:
            sim.run_simulation(duration=hours * 3600)
        else:
            for _ in range(steps):
                sim.step_once()
        wall = time.perf_counter() - t0
        return wall, sim.step_count, [a.get_pose().position.tolist() for a in agents]


def main(argv: list[str] | None = None) -> int:
    """Command-line entry."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[0, 100, 10000], metavar="N")
    parser.add_argument("--agents", type=int, default=20, help="agents of the sparse model")
    parser.add_argument("--hours", type=float, default=1.0, help="sim hours of the sparse model")
    args = parser.parse_args(argv)
    for n in args.n:
        step, idle = empty_step_us(n)
        print(f"empty  N={n:>6}: step_once {step:6.2f} us, idle_steps(1000) {idle:6.2f} us")
    stepped = sparse_run(args.agents, args.hours, skip=False)
    skipped = sparse_run(args.agents, args.hours, skip=True)
    if stepped[1:] != skipped[1:]:
        raise SystemExit("sparse: skipping changed the outcome")
    print(
        f"sparse {args.agents} agents, {args.hours:g} h ({stepped[1]} steps): "
        f"step_once {stepped[0]:.3f} s, run_simulation {skipped[0]:.3f} s "
        f"({stepped[0] / skipped[0]:.1f}x), same final state"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
