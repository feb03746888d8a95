"""Fleet-scale benchmark: step time, real-time factor, spawn time and memory per agent.

The workload and its report live in :mod:`fleet_async.bench` (also run by ``fleet-async bench``);
see there for what is measured. With ``--incumbent VENV`` the same workload, written against
the reference API (``seed_api_workloads.py fleet``), also runs on pybullet-fleet in that venv,
in its own process, right after each fleet_async run of the same size (sizes up to
``--incumbent-max``), and the report adds its step time and the speed-up.

With ``--numpy-too`` each run of the chosen kernels is followed by one with
``kernels="numpy"`` (the compiled kernels' A/B).

Run:  python benchmarks/fleet_bench.py [--n 100 1000 10000] [--large] [--repeat R] [--sweep]
          [--json] [--profile] [--kernels auto|numpy|numba] [--numpy-too]
          [--incumbent /tmp/pbf [--incumbent-max 10000]]
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


def incumbent_step_ms(venv: str, n: int) -> tuple[float, float]:
    """Mean wall and CPU ms per timed step of the fleet workload on the incumbent (a fresh
    process)."""
    python = str(Path(venv) / "bin" / "python")
    cmd = [python, str(HERE / "seed_api_workloads.py"), "--package", "pybullet_fleet"]
    out = subprocess.run([*cmd, "fleet", str(n)], capture_output=True, text=True, check=True)
    result = json.loads(out.stdout.strip().splitlines()[-1])
    return float(result["step_ms"]), float(result["step_cpu_ms"])


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: fleet_async.bench's options plus ``--incumbent``."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    bench.add_arguments(parser)
    parser.add_argument("--incumbent", metavar="VENV", help="pybullet-fleet venv to compare with")
    parser.add_argument(
        "--numpy-too",
        action="store_true",
        help="also run each size with kernels='numpy', interleaved, and report the ratio",
    )
    parser.add_argument(
        "--incumbent-max",
        type=int,
        default=10000,
        metavar="N",
        help="largest size also run on the incumbent (default %(default)s)",
    )
    args = parser.parse_args(argv)
    if args.incumbent is None and not args.numpy_too:
        try:
            return bench.run_from_args(args)
        except ValueError as exc:
            parser.error(str(exc))
    sizes = [*(args.n or bench.DEFAULT_SIZES), *([bench.LARGE_SIZE] if args.large else [])]
    for n in sizes:
        ours: list[dict[str, Any]] = []
        plain: list[dict[str, Any]] = []
        theirs: list[tuple[float, float]] = []
        for i in range(max(1, args.repeat)):  # interleaved: every side sees the same machine
            ours.append(bench.run(n, args.profile, args.sweep, i == 0, args.kernels))
            if args.numpy_too:
                plain.append(bench.run(n, args.profile, args.sweep, False, "numpy"))
            if args.incumbent is not None and n <= args.incumbent_max:
                theirs.append(incumbent_step_ms(args.incumbent, n))
        result = bench.summarize(ours)
        if plain:
            numpy_side = bench.summarize(plain)
            for key in ("step_ms", "step_cpu_ms"):
                result[f"numpy_{key}"] = numpy_side[key]
                result[f"numpy_{key}_runs"] = numpy_side[f"{key}_runs"]
        if theirs:
            result["incumbent_step_ms_runs"] = [wall for wall, _ in theirs]
            result["incumbent_step_cpu_ms_runs"] = [cpu for _, cpu in theirs]
            result["incumbent_step_ms"] = statistics.median(result["incumbent_step_ms_runs"])
            result["incumbent_step_cpu_ms"] = statistics.median(
                result["incumbent_step_cpu_ms_runs"]
            )
            result["speedup"] = result["incumbent_step_ms"] / result["step_ms"]
            result["speedup_cpu"] = result["incumbent_step_cpu_ms"] / result["step_cpu_ms"]
        if args.json:
            print(json.dumps(result), flush=True)
            continue
        print(bench.format_result(result), flush=True)
        if plain:
            runs = ", ".join(f"{ms:.3f}" for ms in result["numpy_step_cpu_ms_runs"])
            print(
                f"    kernels=numpy: step {result['numpy_step_ms']:8.3f} ms "
                f"(CPU {result['numpy_step_cpu_ms']:.3f}; CPU runs {runs})",
                flush=True,
            )
        if theirs:
            runs = ", ".join(f"{ms:.3f}" for ms in result["incumbent_step_ms_runs"])
            print(
                f"    pybullet-fleet: step {result['incumbent_step_ms']:8.3f} ms "
                f"(CPU {result['incumbent_step_cpu_ms']:.3f}; runs {runs})  "
                f"speed-up {result['speedup']:.1f}x (CPU {result['speedup_cpu']:.1f}x)",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
