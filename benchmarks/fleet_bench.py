"""Fleet-scale benchmark: step time, real-time factor, spawn time and memory per agent.

Memory is reported two ways: the Python heap that spawning adds (tracemalloc, measured in a
separate spawn so tracing does not slow the timed run) and the process RSS growth during the
timed spawn (which includes PyBullet's own per-body memory).

Workload (the same for every N): N box robots (0.1 m cube, kinematic) on a ceil(sqrt(N)) grid
with 1 m spacing at z = 0.1; half of them, chosen with a fixed seed, get one goal uniform in
(-10, g + 10) on x and y (g = grid side in m); omni controller with max_linear_vel 2.0 and
max_angular_vel 3.0; timestep 0.1 s; collision checks every step (NORMAL_3D, closest points,
margin 0.02 m); 10 warm-up steps, then 100 timed step_once() calls.

Run:  python benchmarks/fleet_bench.py [--n 100 1000 10000] [--json] [--profile]
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import sys
import time
import tracemalloc

import numpy as np

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimulationParams,
)

WARMUP_STEPS = 10
TIMED_STEPS = 100
TIMESTEP = 0.1


def spawn_fleet(sim: MultiRobotSimulationCore, n: int) -> list[Agent]:
    """N agents on a square grid, 1 m apart, z = 0.1."""
    side = math.ceil(math.sqrt(n))
    cube = ShapeParams("box", half_extents=[0.05, 0.05, 0.05])
    controller = {"type": "omni", "max_linear_vel": 2.0, "max_angular_vel": 3.0}
    params = [
        AgentSpawnParams(
            visual_shape=cube,
            collision_shape=cube,
            initial_pose=Pose.from_xyz(float(i % side), float(i // side), 0.1),
            mass=0.0,
            controller=controller,
        )
        for i in range(n)
    ]
    return Agent.spawn_batch(params, sim)


def _rss_bytes() -> int:
    """Resident set size of this process (Linux /proc; 0 elsewhere)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * 4096
    except OSError:
        return 0


def _params() -> SimulationParams:
    return SimulationParams(
        gui=False,
        monitor=False,
        target_rtf=0.0,
        timestep=TIMESTEP,
        collision_detection_method="closest_points",
        collision_margin=0.02,
        collision_check_frequency=None,
        enable_floor=False,
    )


def python_heap_per_agent(n: int) -> float:
    """KB of Python heap (tracemalloc) that spawning N agents adds, per agent."""
    gc.collect()
    with MultiRobotSimulationCore(_params()) as sim:
        tracemalloc.start()
        base = tracemalloc.get_traced_memory()[0]
        agents = spawn_fleet(sim, n)
        used = tracemalloc.get_traced_memory()[0] - base
        tracemalloc.stop()
        del agents
    return used / 1024.0 / n


def run(n: int, profile: bool = False) -> dict[str, float]:
    """Run the workload for N agents; return the figures."""
    gc.collect()
    with MultiRobotSimulationCore(_params()) as sim:
        rss0 = _rss_bytes()
        t0 = time.perf_counter()
        agents = spawn_fleet(sim, n)
        spawn_s = time.perf_counter() - t0
        rss_bytes = _rss_bytes() - rss0
        rng = np.random.default_rng(42)
        side = math.ceil(math.sqrt(n))
        movers = rng.choice(n, size=n // 2, replace=False)
        goals = rng.uniform(-10.0, side + 10.0, size=(len(movers), 2))
        for idx, (gx, gy) in zip(movers.tolist(), goals.tolist(), strict=True):
            agents[idx].set_goal_pose(Pose.from_xyz(gx, gy, 0.1))
        for _ in range(WARMUP_STEPS):
            sim.step_once()
        phases: dict[str, float] = {}
        t0 = time.perf_counter()
        for _ in range(TIMED_STEPS):
            timings = sim.step_once(return_profiling=profile)
            for key, value in (timings or {}).items():
                phases[key] = phases.get(key, 0.0) + value / TIMED_STEPS
        step_ms = (time.perf_counter() - t0) * 1000.0 / TIMED_STEPS
        moving = sum(a.is_moving for a in agents)
        collisions = sim.collision_count
    result = {
        "n": n,
        "step_ms": step_ms,
        "real_time_factor": TIMESTEP * 1000.0 / step_ms,
        "spawn_s": spawn_s,
        "python_heap_kb_per_agent": python_heap_per_agent(n),
        "rss_kb_per_agent": rss_bytes / 1024.0 / n,
        "moving_after": moving,
        "collisions": collisions,
    }
    if profile:
        result["phases_ms"] = phases  # type: ignore[assignment]
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[100, 1000, 10000], help="fleet sizes")
    parser.add_argument("--large", action="store_true", help="also run 50,000 agents")
    parser.add_argument("--json", action="store_true", help="print one JSON object per size")
    parser.add_argument(
        "--profile", action="store_true", help="add a per-phase breakdown (ms/step)"
    )
    args = parser.parse_args(argv)
    sizes = [*args.n, *([50000] if args.large else [])]
    for n in sizes:
        result = run(n, profile=args.profile)
        if args.json:
            print(json.dumps(result))
        else:
            print(
                f"N={n:>6}: step {result['step_ms']:8.3f} ms  "
                f"RTF {result['real_time_factor']:8.1f}x  spawn {result['spawn_s']:6.3f} s  "
                f"heap {result['python_heap_kb_per_agent']:5.2f} KB/agent  "
                f"RSS {result['rss_kb_per_agent']:5.2f} KB/agent  collisions {result['collisions']}"
            )
            if args.profile:
                for key, value in sorted(result["phases_ms"].items(), key=lambda kv: -kv[1]):  # type: ignore[union-attr]
                    print(f"    {key:<20} {value:8.3f} ms")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
