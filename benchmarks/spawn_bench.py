"""Per-agent spawning as users write it: a loop of ``Agent.from_mesh`` (or ``from_urdf``) calls.

Each size runs in a fresh process (``seed_api_workloads.py spawn``): N agents spawned one call
at a time with ``sim_core=sim``, timed up to the end of the first ``step_once()`` so that work
an implementation defers to the step is counted. fleet_async creates the PyBullet bodies of
such a loop only when something needs them (raw PyBullet access, a recording, physics...),
all in batches; ``+bodies`` is that creation, forced by reading ``sim.client`` afterwards.
With ``--incumbent VENV`` the same script runs on pybullet-fleet in that venv, interleaved with
fleet_async run by run, and the report shows both and the ratio. Figures are medians of wall
time and of the process's CPU time (steadier on a shared machine); the ratio is on CPU time.

``--urdf PATH`` (a file or a model name such as ``husky`` or ``mobile_manipulator``) spawns a
fleet of that one URDF (``--kind urdf``): fleet_async loads the model once and later robots wait
for their bodies (``world/urdf_models.py``); ``+bodies`` is the time to load them all.

Run:  python benchmarks/spawn_bench.py [--n 1000 10000 100000] [--kind mesh|urdf|loaded]
          [--urdf husky] [--spacing 2.0] [--repeat 3] [--incumbent /tmp/pbf] [--json]
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


def run_one(
    python: str, package: str, n: int, kind: str, model: str, spacing: float | None
) -> dict[str, Any]:
    """Run one spawn measurement in a fresh process; return its JSON result."""
    env = dict(os.environ)
    if package == "fleet_async":
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(HERE.parent), env.get("PYTHONPATH")]))
    cmd = [python, str(WORKLOADS), "--package", package, "spawn", str(n), "--kind", kind]
    cmd += ["--model", model]
    if spacing is not None:
        cmd += ["--spacing", str(spacing)]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True, cwd=HERE)
    # PyBullet's C-level warnings (husky's links without inertia) share stdout, unterminated.
    last = out.stdout.strip().splitlines()[-1]
    return json.loads(last[last.index("{") :])


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
    parser.add_argument("--urdf", metavar="PATH", help="same as --kind urdf --model PATH")
    parser.add_argument("--spacing", type=float, help="grid spacing, m (1 mesh, 2 others)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per size and side (median)")
    parser.add_argument("--incumbent", metavar="VENV", help="pybullet-fleet venv to compare with")
    parser.add_argument("--json", action="store_true", help="one JSON object per size")
    args = parser.parse_args(argv)
    if args.urdf:
        args.kind, args.model = "urdf", args.urdf
    model = args.model or str(HERE.parent / "fleet_async" / "data" / "robots" / "mobile_robot.urdf")
    if args.kind == "urdf" and not Path(model).is_file():  # a model name: both sides get a file
        sys.path.insert(0, str(HERE.parent))
        from fleet_async.core.bodies.models import resolve_model

        model = resolve_model(model)
    incumbent = None if args.incumbent is None else str(Path(args.incumbent) / "bin" / "python")
    for n in args.n:
        ours: list[dict[str, Any]] = []
        theirs: list[dict[str, Any]] = []
        for _ in range(args.repeat):  # interleaved, so both sides see the same machine
            ours.append(run_one(sys.executable, "fleet_async", n, args.kind, model, args.spacing))
            if incumbent is not None:
                theirs.append(
                    run_one(incumbent, "pybullet_fleet", n, args.kind, model, args.spacing)
                )
        row: dict[str, Any] = {
            "n": n,
            "kind": args.kind,
            "model": model if args.kind == "urdf" else None,
            "spacing_m": ours[0]["spacing_m"],
            "load_average": os.getloadavg()[0],
        }
        for name, runs in (("fleet_async", ours), ("incumbent", theirs)):
            for field in ("spawn_s", "spawn_cpu_s", "bodies_s", "bodies_cpu_s"):
                if runs:
                    row[f"{name}_{field}"] = [r[field] for r in runs]
        med = {k: statistics.median(v) for k, v in row.items() if isinstance(v, list)}
        if theirs:
            for key in ("spawn_s", "spawn_cpu_s"):
                mine, other = row[f"fleet_async_{key}"], row[f"incumbent_{key}"]
                row[f"speedup_median_{key}"] = med[f"incumbent_{key}"] / med[f"fleet_async_{key}"]
                row[f"speedup_pairs_{key}"] = statistics.median(
                    t / o for o, t in zip(mine, other, strict=True)
                )
        if args.json:
            print(json.dumps(row), flush=True)
            continue
        print(_report(row, Path(model).name if args.kind == "urdf" else ""), flush=True)
    return 0


def _report(row: dict[str, Any], model: str) -> str:
    def runs(key: str) -> str:
        values = row[key]
        return f"{statistics.median(values):7.3f} s (runs {', '.join(f'{t:.3f}' for t in values)})"

    what = f"{row['kind']} {model}".strip()
    text = f"N={row['n']:>7} {what} ({row['spacing_m']:g} m apart, load"
    text += f" {row['load_average']:.1f}): fleet_async {runs('fleet_async_spawn_s')}, CPU"
    text += f" {runs('fleet_async_spawn_cpu_s')}; +bodies"
    text += f" {statistics.median(row['fleet_async_bodies_s']):.3f} s, CPU"
    text += f" {statistics.median(row['fleet_async_bodies_cpu_s']):.3f} s"
    if "incumbent_spawn_s" in row:
        text += f"\n          incumbent {runs('incumbent_spawn_s')}, CPU"
        text += f" {runs('incumbent_spawn_cpu_s')}"
        text += f"\n          speed-up: wall {row['speedup_median_spawn_s']:.1f}x of the medians,"
        text += f" {row['speedup_pairs_spawn_s']:.1f}x per pair; CPU"
        text += f" {row['speedup_median_spawn_cpu_s']:.1f}x of the medians,"
        text += f" {row['speedup_pairs_spawn_cpu_s']:.1f}x per pair"
    return text


if __name__ == "__main__":
    raise SystemExit(main())
