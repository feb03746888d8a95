"""Fleet-scale benchmark: step time, real-time factor, spawn time and memory per agent.

Memory is reported two ways: the Python heap that spawning adds (tracemalloc, measured in a
separate spawn so tracing does not slow the timed run) and the process RSS growth during the
timed spawn (which includes PyBullet's own per-body memory).

Workload (the same for every N): N box robots (0.1 m cube, kinematic) on a ceil(sqrt(N)) grid
with 1 m spacing at z = 0.1; half of them, chosen with a fixed seed, get one goal uniform in
(-10, g + 10) on x and y (g = grid side in m); omni controller with max_linear_vel 2.0 and
max_angular_vel 3.0; timestep 0.1 s; collision checks every step (NORMAL_3D, closest points,
margin 0.02 m; swept with ``--sweep``); 10 warm-up steps, then 100 timed step_once() calls.
With ``--repeat R`` each size runs R times, each in a fresh simulation, and the median step
time is reported beside every run's (memory is measured in the first).

With ``--realistic`` it runs the realistic-fleet workload instead (batteries, patrols,
random walks, missions, carried totes, per-object callbacks, KPIs; see
``fleet_async/realistic_bench.py``), by default at 1,000 and 10,000 robots.

Run:  fleet-async bench [--n 100 1000 10000] [--large] [--repeat R] [--sweep] [--json]
          [--profile] [--realistic [--seconds S]]
 or:  python benchmarks/fleet_bench.py (the same flags, and --incumbent VENV)
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import json
import math
import statistics
import sys
import time
import tracemalloc
from typing import Any, TextIO

import numpy as np

from fleet_async.core.agents.agent import Agent
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.base.compiled import KERNEL_MODES, use_numba
from fleet_async.core.base.params import SimulationParams
from fleet_async.core.base.types import CollisionDetectionMethod
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.simulation import MultiRobotSimulationCore
from fleet_async.core.world.shapes import ShapeParams

__all__ = [
    "DEFAULT_SIZES",
    "LARGE_SIZE",
    "TIMED_STEPS",
    "TIMESTEP",
    "WARMUP_STEPS",
    "add_arguments",
    "bench_params",
    "format_result",
    "main",
    "python_heap_per_agent",
    "run",
    "run_from_args",
    "run_repeated",
    "set_goals",
    "spawn_fleet",
    "summarize",
]

WARMUP_STEPS = 10
TIMED_STEPS = 100
TIMESTEP = 0.1
"""Sim seconds per step of the workload."""
DEFAULT_SIZES = (100, 1000, 10000)
LARGE_SIZE = 100000
"""The fleet size ``--large`` adds."""
SEED = 42
"""Seed of the generator that picks the movers and their goals."""


def spawn_fleet(sim: MultiRobotSimulationCore, n: int) -> list[Agent]:
    """Spawn N box agents on a square grid, 1 m apart, at z = 0.1 m (world frame)."""
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
    """Resident set size of this process in bytes (Linux /proc; 0 elsewhere)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * 4096
    except OSError:
        return 0


def bench_params() -> SimulationParams:
    """The workload's simulation settings: headless, unpaced, dt = 0.1 s, no floor."""
    return SimulationParams(
        gui=False,
        monitor=False,
        target_rtf=0.0,
        timestep=TIMESTEP,
        collision_detection_method=CollisionDetectionMethod.CLOSEST_POINTS,
        collision_margin=0.02,
        collision_check_frequency=None,
        enable_floor=False,
    )


def python_heap_per_agent(n: int) -> float:
    """KB of Python heap (tracemalloc) that spawning N agents adds, per agent."""
    gc.collect()
    with MultiRobotSimulationCore(bench_params()) as sim:
        tracemalloc.start()
        base = tracemalloc.get_traced_memory()[0]
        agents = spawn_fleet(sim, n)
        used = tracemalloc.get_traced_memory()[0] - base
        tracemalloc.stop()
        del agents
    return used / 1024.0 / n


def set_goals(agents: list[Agent], n: int) -> None:
    """Give half the agents (chosen with :data:`SEED`) one goal each."""
    rng = np.random.default_rng(SEED)
    side = math.ceil(math.sqrt(n))
    movers = rng.choice(n, size=n // 2, replace=False)
    goals = rng.uniform(-10.0, side + 10.0, size=(len(movers), 2))
    for idx, (gx, gy) in zip(movers.tolist(), goals.tolist(), strict=True):
        agents[idx].set_goal_pose(Pose.from_xyz(gx, gy, 0.1))


def run(
    n: int,
    profile: bool = False,
    sweep: bool = False,
    memory: bool = True,
    kernels: str = "auto",
) -> dict[str, Any]:
    """Run the workload for N agents.

    Args:
        n: Fleet size.
        profile: Also return ``phases_ms``: mean ms per timed step of each step phase.
        sweep: Run with ``collision_sweep=True``.
        memory: Measure the Python heap per agent (a second, traced spawn); else None.
        kernels: ``SimulationParams.kernels`` ("auto", "numpy" or "numba").

    Returns:
        ``n``, ``step_ms`` (mean wall ms per timed step), ``step_cpu_ms`` (mean CPU ms of this
        process per timed step), ``kernels`` (which ran: "numpy" or "numba"),
        ``real_time_factor``, ``spawn_s``
        (wall seconds), ``python_heap_kb_per_agent``, ``rss_kb_per_agent``, ``moving_after``
        (agents still moving after the timed steps), ``collisions``, ``collision_sweep`` and,
        with ``profile``, ``phases_ms``.
    """
    gc.collect()
    params = dataclasses.replace(bench_params(), collision_sweep=sweep, kernels=kernels)
    with MultiRobotSimulationCore(params) as sim:
        rss0 = _rss_bytes()
        t0 = time.perf_counter()
        agents = spawn_fleet(sim, n)
        spawn_s = time.perf_counter() - t0
        rss_bytes = _rss_bytes() - rss0
        set_goals(agents, n)
        # Collect before the warm-up, not after: a collection walks the whole heap, and the
        # step right after it runs on cold caches (at 100 robots 4-6x slower than the next).
        gc.collect()
        for _ in range(WARMUP_STEPS):
            sim.step_once()
        phases: dict[str, float] = {}
        c0, t0 = time.process_time(), time.perf_counter()
        for _ in range(TIMED_STEPS):
            timings = sim.step_once(return_profiling=profile)
            for key, value in (timings or {}).items():
                if isinstance(value, float):  # not the nested collision_breakdown
                    phases[key] = phases.get(key, 0.0) + value / TIMED_STEPS
        step_ms = (time.perf_counter() - t0) * 1000.0 / TIMED_STEPS
        step_cpu_ms = (time.process_time() - c0) * 1000.0 / TIMED_STEPS
        moving = sum(a.is_moving for a in agents)
        collisions = sim.collision_count
    result: dict[str, Any] = {
        "n": n,
        "step_ms": step_ms,
        "step_cpu_ms": step_cpu_ms,
        "kernels": "numba" if use_numba(kernels) else "numpy",
        "real_time_factor": TIMESTEP * 1000.0 / step_ms,
        "spawn_s": spawn_s,
        "python_heap_kb_per_agent": python_heap_per_agent(n) if memory else None,
        "rss_kb_per_agent": rss_bytes / 1024.0 / n,
        "moving_after": moving,
        "collisions": collisions,
        "collision_sweep": sweep,
    }
    if profile:
        result["phases_ms"] = phases
    return result


def run_repeated(
    n: int, repeat: int = 1, profile: bool = False, sweep: bool = False, kernels: str = "auto"
) -> dict[str, Any]:
    """:func:`run` ``repeat`` times (fresh simulations); the first run's result with
    ``step_ms`` / ``step_cpu_ms`` the medians of all and ``step_ms_runs`` /
    ``step_cpu_ms_runs`` every run's, in order."""
    runs = [run(n, profile, sweep, i == 0, kernels) for i in range(max(1, repeat))]
    return summarize(runs)


def summarize(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The first of several :func:`run` results with the medians and every run's times."""
    result = dict(runs[0])
    for key in ("step_ms", "step_cpu_ms"):
        result[f"{key}_runs"] = [r[key] for r in runs]
        result[key] = statistics.median(result[f"{key}_runs"])
    result["real_time_factor"] = TIMESTEP * 1000.0 / result["step_ms"]
    return result


def format_result(result: dict[str, Any]) -> str:
    """The human-readable report of one :func:`run` result (lines joined by newlines)."""
    runs = result.get("step_ms_runs") or [result["step_ms"]]
    lines = [
        f"N={result['n']:>6}: step {result['step_ms']:8.3f} ms "
        f"(CPU {result.get('step_cpu_ms', math.nan):.3f}, {result.get('kernels', '?')})  "
        f"RTF {result['real_time_factor']:8.1f}x  spawn {result['spawn_s']:6.3f} s  "
        f"heap {result['python_heap_kb_per_agent'] or 0.0:5.2f} KB/agent  "
        f"RSS {result['rss_kb_per_agent']:5.2f} KB/agent  collisions {result['collisions']}"
        + (" (swept)" if result.get("collision_sweep") else "")
    ]
    if len(runs) > 1:
        lines.append("    step ms per run: " + ", ".join(f"{ms:.3f}" for ms in runs))
        cpu = result.get("step_cpu_ms_runs") or []
        lines.append("    CPU ms per run:  " + ", ".join(f"{ms:.3f}" for ms in cpu))
    phases = result.get("phases_ms")
    if phases is not None:
        for key, value in sorted(phases.items(), key=lambda kv: -kv[1]):
            lines.append(f"    {key:<20} {value:8.3f} ms")
    return "\n".join(lines)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the benchmark's options (``--n``, ``--large``, ``--json``, ``--profile``)."""
    parser.add_argument(
        "--n",
        type=int,
        nargs="+",
        default=None,
        metavar="N",
        help=f"fleet sizes (agents) to run, in order (default: {list(DEFAULT_SIZES)}; "
        "with --realistic [1000, 10000])",
    )
    parser.add_argument(
        "--large", action="store_true", help=f"also run {LARGE_SIZE:,} agents (after --n)"
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object per size (keys: n, step_ms, step_ms_runs, "
        "real_time_factor, spawn_s, python_heap_kb_per_agent, rss_kb_per_agent, moving_after, "
        "collisions, collision_sweep)",
    )
    parser.add_argument(
        "--profile", action="store_true", help="add a per-phase breakdown (ms/step)"
    )
    parser.add_argument(
        "--repeat",
        type=int,
        default=1,
        metavar="R",
        help="runs per size, each in a fresh simulation; report the median (default 1)",
    )
    parser.add_argument(
        "--sweep", action="store_true", help="run with collision_sweep=True (swept checks)"
    )
    parser.add_argument(
        "--kernels",
        choices=KERNEL_MODES,
        default="auto",
        help="SimulationParams.kernels: compiled numba kernels when installed (auto), "
        "never (numpy) or required (numba) (default %(default)s)",
    )
    parser.add_argument(
        "--realistic",
        action="store_true",
        help="the realistic-fleet workload (batteries, patrols, random walks, missions, "
        "totes, callbacks, KPIs) instead of bare boxes",
    )
    parser.add_argument(
        "--seconds",
        type=float,
        default=30.0,
        metavar="S",
        help="with --realistic: sim seconds to run, warm-up included (default 30)",
    )


def run_from_args(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """Run every requested size and print its report; return the exit code (0)."""
    stream = out if out is not None else sys.stdout
    if getattr(args, "realistic", False):
        from fleet_async import realistic_bench

        if args.repeat < 1:
            raise ValueError(f"--repeat: expected a number of runs >= 1, got {args.repeat}")
        if not args.seconds > 5.0:
            raise ValueError(f"--seconds: expected more than the 5 s warm-up, got {args.seconds}")
        return realistic_bench.run_from_args(args, stream)
    sizes = [*(args.n or DEFAULT_SIZES), *([LARGE_SIZE] if args.large else [])]
    for n in sizes:
        if n <= 0:
            raise ValueError(f"--n: fleet sizes must be > 0, got {n}")
    if args.repeat < 1:
        raise ValueError(f"--repeat: expected a number of runs >= 1, got {args.repeat}")
    for n in sizes:
        result = run_repeated(n, args.repeat, args.profile, args.sweep, args.kernels)
        print(json.dumps(result) if args.json else format_result(result), file=stream)
        stream.flush()
    return 0


def main(argv: list[str] | None = None) -> int:
    """Command-line entry of ``benchmarks/fleet_bench.py``."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    add_arguments(parser)
    args = parser.parse_args(argv)
    try:
        return run_from_args(args)
    except ValueError as exc:
        parser.error(str(exc))  # exits with code 2
