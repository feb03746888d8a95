"""Per-agent spawning as users write it: a loop of ``Agent.from_mesh`` (or ``from_urdf``) calls.

Each size runs in a fresh process (``seed_api_workloads.py spawn``): N agents spawned one call
at a time with ``sim_core=sim``, timed up to the end of the first ``step_once()`` so that work
an implementation defers to the step is counted. fleet_async creates the PyBullet bodies of
such a loop only when something needs them (raw PyBullet access, a recording, physics...),
all in batches; ``+bodies`` is that creation, forced by reading ``sim.client`` afterwards.
With ``--incumbent VENV`` the same script runs on pybullet-fleet in that venv, interleaved with
fleet_async run by run, and the report shows both and the ratio.

Run:  python benchmarks/spawn_bench.py [--n 1000 10000 100000] [--kind mesh|urdf|loaded]
          [--repeat 3] [--incumbent /tmp/pbf] [--json]
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


def run_one(python: str, package: str, n: int, kind: str, model: str) -> dict[str, Any]:
    """Run one spawn measurement in a fresh process; return its JSON result."""
    env = dict(os.environ)
    if package == "fleet_async":
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(HERE.parent), env.get("PYTHONPATH")]))
    cmd = [python, str(WORKLOADS), "--package", package, "spawn", str(n), "--kind", kind]
    cmd += ["--model", model]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True, cwd=HERE)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    """Command-line entry."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[1000, 10000], metavar="N")
    parser.add_argument("--kind", choices=("mesh", "urdf", "loaded"), default="mesh")
    parser.add_argument(
        "--model",
        default=None,
        help="URDF for --kind urdf (default: fleet_async's mobile_robot.urdf, for both sides)",
    )
    parser.add_argument("--repeat", type=int, default=3, help="runs per size and side (median)")
    parser.add_argument("--incumbent", metavar="VENV", help="pybullet-fleet venv to compare with")
    parser.add_argument("--json", action="store_true", help="one JSON object per size")
    args = parser.parse_args(argv)
    model = args.model or str(HERE.parent / "fleet_async" / "data" / "robots" / "mobile_robot.urdf")
    incumbent = None if args.incumbent is None else str(Path(args.incumbent) / "bin" / "python")
    for n in args.n:
        ours: list[dict[str, Any]] = []
        theirs: list[dict[str, Any]] = []
        for _ in range(args.repeat):  # interleaved, so both sides see the same machine
            ours.append(run_one(sys.executable, "fleet_async", n, args.kind, model))
            if incumbent is not None:
                theirs.append(run_one(incumbent, "pybullet_fleet", n, args.kind, model))
        row: dict[str, Any] = {
            "n": n,
            "kind": args.kind,
            "fleet_async_s": [r["spawn_s"] for r in ours],
            "fleet_async_cpu_s": [r["spawn_cpu_s"] for r in ours],
            "fleet_async_bodies_s": [r["bodies_s"] for r in ours],
        }
        if theirs:
            row["incumbent_s"] = [r["spawn_s"] for r in theirs]
            row["incumbent_cpu_s"] = [r["spawn_cpu_s"] for r in theirs]
            for key in ("s", "cpu_s"):
                mine, other = row[f"fleet_async_{key}"], row[f"incumbent_{key}"]
                row[f"speedup_median_{key}"] = statistics.median(other) / statistics.median(mine)
                row[f"speedup_pairs_{key}"] = statistics.median(
                    t / o for o, t in zip(mine, other, strict=True)
                )
            row["speedup_median"] = row["speedup_median_s"]
        if args.json:
            print(json.dumps(row), flush=True)
            continue
        print(_report(row, theirs != []), flush=True)
    return 0


def _report(row: dict[str, Any], incumbent: bool) -> str:
    def runs(key: str) -> str:
        values = row[key]
        return f"{statistics.median(values):7.3f} s (runs {', '.join(f'{t:.3f}' for t in values)})"

    text = f"N={row['n']:>7} {row['kind']}: fleet_async {runs('fleet_async_s')}, CPU"
    text += f" {runs('fleet_async_cpu_s')}; +bodies"
    text += f" {statistics.median(row['fleet_async_bodies_s']):.3f} s"
    if incumbent:
        text += f"\n          incumbent {runs('incumbent_s')}, CPU {runs('incumbent_cpu_s')}"
        text += f"\n          speed-up: wall {row['speedup_median_s']:.1f}x of the medians,"
        text += f" {row['speedup_pairs_s']:.1f}x per pair; CPU {row['speedup_median_cpu_s']:.1f}x"
        text += f" of the medians, {row['speedup_pairs_cpu_s']:.1f}x per pair"
    return text


if __name__ == "__main__":
    raise SystemExit(main())
