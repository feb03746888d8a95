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
        ours: list[float] = []
        bodies: list[float] = []
        theirs: list[float] = []
        for _ in range(args.repeat):  # interleaved, so both sides see the same machine
            mine = run_one(sys.executable, "fleet_async", n, args.kind, model)
            ours.append(mine["spawn_s"])
            bodies.append(mine["bodies_s"])
            if incumbent is not None:
                theirs.append(run_one(incumbent, "pybullet_fleet", n, args.kind, model)["spawn_s"])
        row: dict[str, Any] = {
            "n": n,
            "kind": args.kind,
            "fleet_async_s": ours,
            "fleet_async_bodies_s": bodies,
        }
        if theirs:
            row["incumbent_s"] = theirs
            row["speedup_median"] = statistics.median(theirs) / statistics.median(ours)
        if args.json:
            print(json.dumps(row), flush=True)
            continue
        text = f"N={n:>7} {args.kind}: fleet_async {statistics.median(ours):7.3f} s"
        text += f" (runs {', '.join(f'{t:.3f}' for t in ours)};"
        text += f" +bodies {statistics.median(bodies):.3f} s)"
        if theirs:
            text += f"  incumbent {statistics.median(theirs):7.3f} s"
            text += f" (runs {', '.join(f'{t:.3f}' for t in theirs)})"
            text += f"  speed-up {row['speedup_median']:.1f}x"
        print(text, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
