"""What a trace costs: step time with and without ``sim.start_trace``, side by side.

The workload is ``fleet_async.bench``'s (N box robots on a grid, half of them driving to a
random goal, collision checks every step; 10 warm-up steps, then 300 timed steps). Each repeat
runs the workload twice on fresh simulations, once untraced and once traced (a frame every
step), in alternating order (A/B interleaved), so a slow patch of a shared machine hits both
modes. Reported: the median and best step time of each mode (wall and process CPU time), the
overhead of the medians and the median of the pairs' ratios, and the trace's size per robot
per frame.

Because a busy shared machine makes step-time differences of a few percent noisy, the cost is
also attributed directly: the simulation thread's CPU time in the writer's step observer
(copying the frame out, handing chunks to the writer thread) and in its collision listener
(one call per check with the check's arrays of pairs), measured in the traced runs, as a share
of the untraced step's CPU time. The writer thread (file writes) runs on another core and is
counted in the traced runs' CPU time.

Run:  python benchmarks/trace_bench.py [--n 10000] [--repeat 5] [--every 1] [--steps 300] [--json]
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import statistics
import tempfile
import time
from typing import Any

from fleet_async.bench import WARMUP_STEPS, bench_params, set_goals, spawn_fleet
from fleet_async.core import MultiRobotSimulationCore
from fleet_async.core.view.trace import TraceWriter
from fleet_async.viewer import TraceReader


def _timed(fn: Any, box: list[float]) -> Any:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t0 = time.thread_time()  # CPU time: other processes' load does not count
        try:
            return fn(*args, **kwargs)
        finally:
            box[0] += time.thread_time() - t0

    return wrapper


def one_run(n: int, trace_path: str | None, every: int, steps: int) -> dict[str, float]:
    """Step time (ms, mean over the timed steps) of one run, traced when ``trace_path``."""
    gc.collect()
    with MultiRobotSimulationCore(bench_params()) as sim:
        agents = spawn_fleet(sim, n)
        set_goals(agents, n)
        for _ in range(WARMUP_STEPS):
            sim.step_once()
        start_s = 0.0
        in_handler = [0.0]
        if trace_path is not None:
            t0 = time.perf_counter()
            writer = TraceWriter(sim, trace_path, every)
            # Time the step observer (frame capture, chunk writes) and the collision listener
            # of this run.
            writer._after_step = _timed(writer._after_step, in_handler)  # type: ignore[method-assign]  # noqa: SLF001
            log = writer._log  # noqa: SLF001
            log._on_collisions = _timed(log._on_collisions, in_handler)  # type: ignore[method-assign]  # noqa: SLF001
            writer.start()
            start_s = time.perf_counter() - t0
        t0, c0 = time.perf_counter(), time.process_time()
        for _ in range(steps):
            sim.step_once()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        t0 = time.perf_counter()
        if trace_path is not None:
            writer.stop()
        stop_s = time.perf_counter() - t0
    return {
        "handler_ms": in_handler[0] * 1000.0 / steps,
        "step_ms": wall * 1000.0 / steps,
        "cpu_ms": cpu * 1000.0 / steps,
        "start_s": start_s,
        "stop_s": stop_s,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--n", type=int, default=10000, help="robots (default 10000)")
    parser.add_argument("--repeat", type=int, default=5, help="A/B pairs (default 5)")
    parser.add_argument("--every", type=int, default=1, help="trace every_n_steps (default 1)")
    parser.add_argument("--steps", type=int, default=300, help="timed steps per run (default 300)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    runs: dict[str, list[dict[str, float]]] = {"off": [], "on": []}
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "bench.fatrace")
        for i in range(args.repeat):
            order = ("off", "on") if i % 2 == 0 else ("on", "off")
            for mode in order:
                trace = path if mode == "on" else None
                runs[mode].append(one_run(args.n, trace, args.every, args.steps))
        size = os.path.getsize(path)
        reader = TraceReader(path)
        frames = reader.frame_count
        pose_bytes = sum(reader.frame_bytes())
        # Collision events per timed step, from the last traced run's file (not counted during
        # the timed steps: a counting handler would cost about as much as the writer's).
        stamped = reader.collisions()["step"]
        timed = (stamped > WARMUP_STEPS) & (stamped <= WARMUP_STEPS + args.steps)
        per_step = float(timed.sum()) / args.steps
    med = {m: statistics.median(r["step_ms"] for r in runs[m]) for m in runs}
    # Each pair ran back to back, so its ratio is the least disturbed by a drifting machine.
    pairs = zip(runs["on"], runs["off"], strict=True)
    paired = [on["step_ms"] / off["step_ms"] for on, off in pairs]
    best = {m: min(r["step_ms"] for r in runs[m]) for m in runs}
    cpu = {m: statistics.median(r["cpu_ms"] for r in runs[m]) for m in runs}
    attributed = statistics.median(r["handler_ms"] for r in runs["on"])
    result = {
        "n": args.n,
        "collision_events_per_step": per_step,
        "attributed_ms": attributed,
        "attributed_pct_of_untraced_step": 100.0 * attributed / med["off"],
        "attributed_pct_of_untraced_cpu": 100.0 * attributed / cpu["off"],
        "repeat": args.repeat,
        "every_n_steps": args.every,
        "step_ms_off": [round(r["step_ms"], 3) for r in runs["off"]],
        "step_ms_on": [round(r["step_ms"], 3) for r in runs["on"]],
        "median_off": med["off"],
        "median_on": med["on"],
        "overhead_pct": 100.0 * (med["on"] - med["off"]) / med["off"],
        "paired_overhead_pct": 100.0 * (statistics.median(paired) - 1.0),
        "best_overhead_pct": 100.0 * (best["on"] - best["off"]) / best["off"],
        "cpu_overhead_pct": 100.0 * (cpu["on"] - cpu["off"]) / cpu["off"],
        "start_s": statistics.median(r["start_s"] for r in runs["on"]),
        "stop_s": statistics.median(r["stop_s"] for r in runs["on"]),
        "file_bytes": size,
        "frames": frames,
        "bytes_per_robot_frame": size / (frames * args.n),
        "pose_bytes_per_robot_frame": pose_bytes / (frames * args.n),
    }
    if args.json:
        print(json.dumps(result))
        return 0
    print(
        f"N = {args.n}, {args.repeat} A/B pairs, {args.steps} timed steps each, a frame "
        f"every {args.every} step(s)"
    )
    print(f"{'run':>4} {'untraced ms':>12} {'traced ms':>10}")
    for i, (off, on) in enumerate(zip(result["step_ms_off"], result["step_ms_on"], strict=True)):
        print(f"{i + 1:>4} {off:>12.3f} {on:>10.3f}")
    print(
        f"median: untraced {med['off']:.3f} ms, traced {med['on']:.3f} ms, "
        f"overhead {result['overhead_pct']:+.1f}% (median of the pairs' ratios: "
        f"{result['paired_overhead_pct']:+.1f}%; best of each: "
        f"{result['best_overhead_pct']:+.1f}%; CPU time: {result['cpu_overhead_pct']:+.1f}%)"
    )
    print(
        f"attributed: step observer and collision listener {attributed:.3f} ms/step "
        f"({per_step:.0f} collision events/step) = "
        f"{result['attributed_pct_of_untraced_cpu']:.1f}% of the untraced step's CPU time "
        f"({result['attributed_pct_of_untraced_step']:.1f}% of its wall time)"
    )
    print(
        f"start_trace {result['start_s'] * 1000:.0f} ms, stop_trace "
        f"{result['stop_s'] * 1000:.0f} ms; file {size / 1e6:.1f} MB for {frames} frames: "
        f"{result['bytes_per_robot_frame']:.2f} bytes per robot per frame "
        f"({result['pose_bytes_per_robot_frame']:.2f} of them pose bytes)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
