"""Fleet-scale benchmark: step time, real-time factor, spawn time and memory per agent.

The workload and its report live in :mod:`fleet_async.bench` (also run by ``fleet-async bench``);
see there for what is measured. With ``--incumbent VENV`` the same workload, written against
the reference API (``seed_api_workloads.py fleet``), also runs on pybullet-fleet in that venv,
in its own process, right after each fleet_async run of the same size (sizes up to
``--incumbent-max``), and the report adds its step time and the speed-up.

Run:  python benchmarks/fleet_bench.py [--n 100 1000 10000] [--large] [--repeat R] [--sweep]
          [--json] [--profile] [--incumbent /tmp/pbf [--incumbent-max 10000]]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Any

from fleet_async import bench

HERE = Path(__file__).resolve().parent


def incumbent_step_ms(venv: str, n: int) -> float:
    """Mean ms per timed step of the fleet workload on the incumbent (a fresh process)."""
    python = str(Path(venv) / "bin" / "python")
    cmd = [python, str(HERE / "seed_api_workloads.py"), "--package", "pybullet_fleet"]
    out = subprocess.run([*cmd, "fleet", str(n)], capture_output=True, text=True, check=True)
    return float(json.loads(out.stdout.strip().splitlines()[-1])["step_ms"])


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: fleet_async.bench's options plus ``--incumbent``."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    bench.add_arguments(parser)
    parser.add_argument("--incumbent", metavar="VENV", help="pybullet-fleet venv to compare with")
    parser.add_argument(
        "--incumbent-max",
        type=int,
        default=10000,
        metavar="N",
        help="largest size also run on the incumbent (default %(default)s)",
    )
    args = parser.parse_args(argv)
    if args.incumbent is None:
        try:
            return bench.run_from_args(args)
        except ValueError as exc:
            parser.error(str(exc))
    sizes = [*(args.n or bench.DEFAULT_SIZES), *([bench.LARGE_SIZE] if args.large else [])]
    for n in sizes:
        ours: list[dict[str, Any]] = []
        theirs: list[float] = []
        for i in range(max(1, args.repeat)):  # interleaved: both sides see the same machine
            ours.append(bench.run(n, args.profile, args.sweep, memory=i == 0))
            if n <= args.incumbent_max:
                theirs.append(incumbent_step_ms(args.incumbent, n))
        result = dict(ours[0])
        result["step_ms_runs"] = [r["step_ms"] for r in ours]
        result["step_ms"] = statistics.median(result["step_ms_runs"])
        result["real_time_factor"] = bench.TIMESTEP * 1000.0 / result["step_ms"]
        if theirs:
            result["incumbent_step_ms_runs"] = theirs
            result["incumbent_step_ms"] = statistics.median(theirs)
            result["speedup"] = result["incumbent_step_ms"] / result["step_ms"]
        if args.json:
            print(json.dumps(result), flush=True)
            continue
        print(bench.format_result(result), flush=True)
        if theirs:
            runs = ", ".join(f"{ms:.3f}" for ms in theirs)
            print(
                f"    pybullet-fleet: step {result['incumbent_step_ms']:8.3f} ms "
                f"(runs {runs})  speed-up {result['speedup']:.1f}x",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
