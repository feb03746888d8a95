"""The realistic fleet, side by side with pybullet-fleet 0.8.0, and fleet_async's full version.

Two workloads (both described in ``fleet_async/realistic_bench.py``):

- ``seed``: the workload in seed-API terms (``seed_api_workloads.py realistic N``: missions
  as action queues, no KPIs), run in fresh processes, fleet_async and (with ``--incumbent``)
  pybullet-fleet in turn, run by run; the ratio is taken pair by pair, on wall and on CPU time
  per step (CPU time is steadier when the machine is shared).
- ``full``: ``fleet-async bench --realistic`` (missions, KPIs), fleet_async only.

Run:  python benchmarks/realistic_bench.py [--n 1000 10000] [--repeat 5] [--incumbent /tmp/pbf08]
          [--incumbent-max 1000] [--full] [--json] [--kernels auto|numpy|numba]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
WORKLOADS = HERE / "seed_api_workloads.py"


def seed_run(
    python: str, package: str, n: int, steps: int, kernels: str | None = None
) -> dict[str, Any]:
    """One run of the seed-API workload in a fresh process; its JSON result (``kernels``:
    fleet_async's ``SimulationParams.kernels``)."""
    env = dict(os.environ)
    if package == "fleet_async":
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(HERE.parent), env.get("PYTHONPATH")]))
    cmd = [python, str(WORKLOADS), "--package", package, "realistic", str(n)]
    cmd += ["--steps", str(steps), *(["--kernels", kernels] if kernels else [])]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True, cwd=HERE)
    return json.loads(out.stdout.strip().splitlines()[-1])


def full_run(n: int, kernels: str) -> dict[str, Any]:
    """One run of ``fleet-async bench --realistic`` in a fresh process."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(HERE.parent), env.get("PYTHONPATH")]))
    cmd = [sys.executable, "-m", "fleet_async", "bench", "--realistic", "--n", str(n), "--json"]
    cmd += ["--kernels", kernels]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True, cwd=HERE)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _median(rows: list[dict[str, Any]], key: str) -> float:
    return statistics.median(r[key] for r in rows)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[1000, 10000], metavar="N")
    parser.add_argument("--repeat", type=int, default=5, help="runs per size and side")
    parser.add_argument("--steps", type=int, default=200, help="timed steps per run")
    parser.add_argument("--incumbent", metavar="VENV", help="pybullet-fleet venv to compare with")
    parser.add_argument("--incumbent-max", type=int, default=1000, metavar="N")
    parser.add_argument("--full", action="store_true", help="also run the full version")
    parser.add_argument("--json", action="store_true", help="one JSON object per size")
    parser.add_argument(
        "--kernels",
        choices=("auto", "numpy", "numba"),
        default="auto",
        help="fleet_async's SimulationParams.kernels (default %(default)s: the compiled "
        "kernels when the fast extra is installed, as fleet-async bench)",
    )
    args = parser.parse_args(argv)
    incumbent = None if args.incumbent is None else str(Path(args.incumbent) / "bin" / "python")
    for n in args.n:
        ours: list[dict[str, Any]] = []
        theirs: list[dict[str, Any]] = []
        full: list[dict[str, Any]] = []
        for _ in range(args.repeat):  # interleaved, so both sides see the same machine
            ours.append(seed_run(sys.executable, "fleet_async", n, args.steps, args.kernels))
            if incumbent is not None and n <= args.incumbent_max:
                theirs.append(seed_run(incumbent, "pybullet_fleet", n, args.steps))
            if args.full:
                full.append(full_run(n, args.kernels))
        row: dict[str, Any] = {"n": n, "fleet_async": ours, "incumbent": theirs, "full": full}
        if theirs:
            for key in ("step_ms", "step_cpu_ms", "spawn_s", "spawn_cpu_s"):
                pairs = [t[key] / o[key] for o, t in zip(ours, theirs, strict=True)]
                row[f"speedup_{key}"] = statistics.median(pairs)
        if args.json:
            print(json.dumps(row), flush=True)
            continue
        text = (
            f"N={n:>6} seed-API realistic: fleet_async step {_median(ours, 'step_ms'):.3f} ms"
            f" (CPU {_median(ours, 'step_cpu_ms'):.3f}; {ours[0].get('kernels', 'numpy')}),"
            f" spawn {_median(ours, 'spawn_s'):.3f} s"
            f" (CPU {_median(ours, 'spawn_cpu_s'):.3f})"
        )
        if theirs:
            text += (
                f"; incumbent step {_median(theirs, 'step_ms'):.2f} ms"
                f" (CPU {_median(theirs, 'step_cpu_ms'):.2f}), spawn"
                f" {_median(theirs, 'spawn_s'):.3f} s (CPU {_median(theirs, 'spawn_cpu_s'):.3f});"
                f" speed-up per pair, median: step {row['speedup_step_ms']:.1f}x"
                f" (CPU {row['speedup_step_cpu_ms']:.1f}x), spawn {row['speedup_spawn_s']:.1f}x"
                f" (CPU {row['speedup_spawn_cpu_s']:.1f}x)"
            )
        if full:
            text += (
                f"\n        full (missions, KPIs): step {_median(full, 'step_ms'):.3f} ms"
                f" (CPU {_median(full, 'step_cpu_ms'):.3f}), spawn {_median(full, 'spawn_s'):.3f} s"
            )
        print(text, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
