"""What the KPI collector costs per step: the fleet benchmark's workload with and without it.

The workload is ``fleet-async bench``'s (N box robots, half of them driving to a goal,
collision checks every step). Two figures per N:

- the collector's own per-step pass (its POST_STEP handler), timed in isolation, and
- the step time of the whole simulation with ``sim.kpis()`` attached and without it, run
  interleaved ``--repeat`` times, best of each.

Run:  python benchmarks/kpi_bench.py [--n 100 1000 10000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from fleet_async import Agent, MultiRobotSimulationCore, Pose, SimEvents
from fleet_async.bench import SEED, TIMED_STEPS, WARMUP_STEPS, bench_params, spawn_fleet


def _set_goals(agents: list[Agent], n: int) -> None:
    """Half the fleet gets one goal each, as in the fleet benchmark."""
    rng = np.random.default_rng(SEED)
    side = math.ceil(math.sqrt(n))
    movers = rng.choice(n, size=n // 2, replace=False)
    goals = rng.uniform(-10.0, side + 10.0, size=(len(movers), 2))
    for idx, (gx, gy) in zip(movers.tolist(), goals.tolist(), strict=True):
        agents[idx].set_goal_pose(Pose.from_xyz(gx, gy, 0.1))


def _step_ms(n: int, with_kpis: bool) -> float:
    with MultiRobotSimulationCore(bench_params()) as sim:
        agents = spawn_fleet(sim, n)
        if with_kpis:
            sim.kpis()
        _set_goals(agents, n)
        for _ in range(WARMUP_STEPS):
            sim.step_once()
        t0 = time.perf_counter()
        for _ in range(TIMED_STEPS):
            sim.step_once()
        return (time.perf_counter() - t0) * 1000.0 / TIMED_STEPS


def _handler_us(n: int, calls: int = 2000) -> float:
    """Microseconds per POST_STEP emit with only the collector listening (its per-step
    pass plus the emit), half the fleet moving."""
    with MultiRobotSimulationCore(bench_params()) as sim:
        agents = spawn_fleet(sim, n)
        sim.kpis()
        _set_goals(agents, n)
        for _ in range(WARMUP_STEPS):
            sim.step_once()
        events = sim.events
        t0 = time.perf_counter()
        for _ in range(calls):
            events.emit(SimEvents.POST_STEP, sim=sim, step=0, sim_time=0.0)
        return (time.perf_counter() - t0) * 1e6 / calls


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[100, 1000, 10000])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    for n in args.n:
        plain = min(_step_ms(n, False) for _ in range(args.repeat))
        with_kpis = min(_step_ms(n, True) for _ in range(args.repeat))
        handler = min(_handler_us(n) for _ in range(args.repeat))
        print(
            f"N={n:>6}: step {plain:7.3f} ms without KPIs, {with_kpis:7.3f} ms with "
            f"({(with_kpis / plain - 1) * 100:+.1f}%); collector pass {handler:6.1f} us/step"
        )


if __name__ == "__main__":
    main()
