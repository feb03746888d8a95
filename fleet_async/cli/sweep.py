"""``fleet-async sweep SCENARIO``: a scenario x a parameter grid x seeds -> a table of fleet KPIs.

SCENARIO is a YAML file (``--set`` keys are dotted paths into it; each run is its missions and
actions, as ``fleet-async run`` runs it) or a Python function ``FILE.py:NAME`` /
``MODULE:NAME`` (``--set`` keys are its keyword parameters). The table is
written as runs finish; running the same command again skips the runs it already has.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from fleet_async.cli.errors import CliError
from fleet_async.cli.progress import RunsProgressBar
from fleet_async.cli.run import INTERRUPTED_EXIT_CODE
from fleet_async.core import FleetKpis
from fleet_async.sweep import (
    ENGINES,
    Engine,
    FunctionScenario,
    Scenario,
    SweepKeyError,
    SweepPlan,
    SweepProgress,
    SweepSummary,
    YamlScenario,
    make_engine,
    parse_assignment,
    parse_seeds,
    run_sweep,
)
from fleet_async.sweep.plot import plot_kpi, require_matplotlib

__all__ = ["EPILOG", "add_arguments", "execute", "load_sweep_scenario"]

FAILED_EXIT_CODE = 1
"""Exit code when the sweep finished but some runs failed (their rows hold the errors)."""

EPILOG = """\
examples:
  fleet-async sweep examples/scenarios/warehouse.yaml --set entities.picker.grid.count=2,4,6 \\
      --out pickers.csv             # each run: the warehouse shift, until it is done
  fleet-async sweep examples/sweep_fleet.py:scenario --seeds 0:25 --set robots=2,4,6,8 \\
      --out fleet.csv --plot fleet.png --x robots --y throughput_per_hour
  fleet-async sweep my_scenario.yaml --keys          # list the keys --set accepts

The table: one row per run, sorted by 'run' (runs are numbered seed-major: every grid point
for the first seed, then the next seed...), then the swept keys, 'seed', the fleet KPIs
(docs/sweeps.md defines them), 'error' (empty unless the run failed) and 'wall_time_s'.
Every column but wall_time_s is identical whichever engine ran the sweep. Ctrl+C stops the
sweep (the runs in progress finish and are written); the same command again continues.
Exit codes: 0 every run succeeded, 1 some runs failed (see their 'error'), 2 bad input,
130 interrupted.
"""


def _seeds(text: str) -> list[int]:
    try:
        return parse_seeds(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix(f"--seeds {text!r}: ")) from None


def _assignment(text: str) -> tuple[str, list[Any]]:
    try:
        return parse_assignment(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _positive_int(text: str) -> int:
    if not text.isdigit() or int(text) <= 0:
        raise argparse.ArgumentTypeError(f"expected a whole number > 0, got {text!r}")
    return int(text)


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``sweep`` options to ``parser``."""
    parser.add_argument(
        "scenario",
        metavar="SCENARIO",
        help="a scenario YAML file, or a Python function FILE.py:NAME or MODULE:NAME called as "
        "NAME(seed, **params) that returns a simulation or (simulation, main mission)",
    )
    parser.add_argument(
        "--seeds",
        type=_seeds,
        default=[0],
        metavar="A:B",
        help="seeds: START:STOP (STOP excluded, e.g. 0:100), START:STOP:STEP, N or A,B,C "
        "(default: 0)",
    )
    parser.add_argument(
        "--set",
        dest="assignments",
        type=_assignment,
        action="append",
        default=[],
        metavar="KEY=V1,V2",
        help="sweep KEY over the values (numbers, true/false, text, [lists]); repeat for a "
        "grid: every combination runs with every seed. --keys lists the valid keys",
    )
    parser.add_argument(
        "--out",
        default="results.csv",
        metavar="FILE",
        help="the table: .csv (default: results.csv) or .parquet (needs pyarrow); an existing "
        "table of the same sweep is continued",
    )
    parser.add_argument(
        "--duration",
        type=_positive_float,
        metavar="S",
        help="sim seconds per run. Default: the scenario's simulation.duration; without one, "
        "until the run's work is done (a scenario file's missions: returned and actions "
        "finished, at most 600 s, as under 'fleet-async run'; a function scenario's main "
        "mission returned)",
    )
    parser.add_argument(
        "--engine",
        choices=ENGINES,
        default="pool",
        help="pool: worker processes on this machine (default); ray: Ray, local or --address "
        "(needs the ray extra); inline: one run at a time in this process (for debugging)",
    )
    parser.add_argument(
        "--address",
        metavar="ADDR",
        help="with --engine ray: an existing Ray cluster (ray://HOST:10001, HOST:6379 or auto)",
    )
    parser.add_argument(
        "--workers",
        type=_positive_int,
        metavar="N",
        help="worker processes of the pool / CPUs of a local Ray (default: one per core)",
    )
    parser.add_argument(
        "--checkpoint",
        metavar="FILE",
        help="branch every run from this checkpoint (fleet-async run --save-state FILE, or "
        "sim.save_state): restored into the freshly built scenario, reseeded with the run's "
        "seed, then run for --duration",
    )
    parser.add_argument(
        "--unsafe",
        action="store_true",
        help="with --checkpoint: also read an old (format 1) checkpoint, a pickle, which runs "
        "any code it names: only for a file whose maker you trust",
    )
    parser.add_argument(
        "--per-robot",
        metavar="FILE",
        help="also write the per-robot table (one row per robot per run) to FILE",
    )
    parser.add_argument(
        "--plot",
        metavar="PNG",
        help="draw --y against --x with its spread over seeds (needs the plot extra)",
    )
    parser.add_argument(
        "--x", metavar="KEY", help="swept key on the plot's x axis (default: the first --set)"
    )
    parser.add_argument(
        "--y",
        metavar="KPI",
        default="throughput_per_hour",
        help="KPI column to plot (default: throughput_per_hour)",
    )
    parser.add_argument(
        "--keys", action="store_true", help="list the keys --set accepts for SCENARIO and exit"
    )
    parser.add_argument(
        "--quiet", action="store_true", help="no progress bar and no summary; errors still print"
    )


def load_sweep_scenario(text: str) -> Scenario:
    """A YAML file, or a ``FILE.py:NAME`` / ``MODULE:NAME`` function reference.

    Raises:
        CliError: for a missing file, bad YAML or an unloadable function.
    """
    path = Path(text)
    try:
        if path.suffix in (".yaml", ".yml") or path.is_file():
            return YamlScenario.from_file(path)
        scenario = FunctionScenario(text)
        scenario.settable_keys()  # loads it now: a broken reference is an error up front
        return scenario
    except (OSError, ValueError, ImportError, SyntaxError) as exc:
        raise CliError(f"{text}: {exc}") from exc


def _check_plot_args(args: argparse.Namespace, keys: list[str]) -> str | None:
    """The x column of --plot (None without --plot)."""
    if not args.plot:
        return None
    if not keys and args.x is None:
        raise CliError("--plot needs a swept parameter for its x axis: give --set KEY=...")
    x = args.x or keys[0]
    if x not in keys and x != "seed":
        raise CliError(f"--x {x}: not a swept key; swept: {', '.join(keys) or '(none)'}")
    if args.y not in FleetKpis.columns():
        raise CliError(f"--y {args.y}: not a KPI; KPIs: {', '.join(FleetKpis.columns())}")
    try:
        require_matplotlib()  # before the sweep, not after an hour of it
    except ImportError as exc:
        raise CliError(str(exc)) from exc
    return x


def _print_summary(summary: SweepSummary, out: str, engine: Engine) -> None:
    print(
        f"{summary.total} runs: {summary.ran} ran on {engine.describe()}, {summary.skipped} "
        f"were already in {out}; {summary.failed} failed; wall time {summary.wall_time_s:.1f} s"
    )
    errors = [row for row in summary.rows if row.get("error") not in (None, "")]
    for row in errors[:5]:
        print(f"  run {row['run']} (seed {row['seed']}): {row['error']}")
    if len(errors) > 5:
        print(f"  ... and {len(errors) - 5} more (the 'error' column of {out})")
    if summary.interrupted:
        print("interrupted: run the same command again to continue")


def execute(args: argparse.Namespace) -> int:
    """Run the ``sweep`` command; return the exit code."""
    scenario = load_sweep_scenario(args.scenario)
    if args.keys:
        keys = scenario.settable_keys()
        print("\n".join(keys) if keys is not None else f"{scenario.label} takes any keyword")
        return 0
    grid: dict[str, list[Any]] = {}
    for key, values in args.assignments:
        if key in grid:
            raise CliError(f"--set {key}: given twice; put every value in one --set")
        grid[key] = values
    x = _check_plot_args(args, list(grid))
    try:
        engine = make_engine(args.engine, args.workers, args.address)
        plan = SweepPlan(grid, args.seeds)
    except (ValueError, ImportError) as exc:
        raise CliError(str(exc)) from exc
    bar: RunsProgressBar | None = None

    def on_progress(progress: SweepProgress) -> None:
        nonlocal bar
        if args.quiet:
            return
        if bar is None:
            bar = RunsProgressBar(progress.total, sys.stderr, skipped=progress.skipped)
            bar.start()
        bar.failed = progress.failed
        bar.update(progress.done)

    try:
        summary = run_sweep(
            scenario,
            plan,
            args.out,
            engine=engine,
            duration=args.duration,
            robots_out=args.per_robot,
            checkpoint=args.checkpoint,
            unsafe=args.unsafe,
            on_progress=on_progress,
        )
    except (SweepKeyError, ValueError, ImportError, RuntimeError) as exc:
        raise CliError(str(exc)) from exc
    if bar is not None:
        bar.finish(summary.skipped + summary.ran)
    if not args.quiet:
        _print_summary(summary, args.out, engine)
    if args.plot and x is not None and not summary.interrupted:
        group_by = [key for key in grid if key != x]
        try:
            plot_kpi(summary.rows, x, args.y, args.plot, group_by=group_by)
        except (ImportError, ValueError) as exc:
            raise CliError(str(exc)) from exc
        if not args.quiet:
            print(f"plot: {args.plot}")
    if summary.interrupted:
        return INTERRUPTED_EXIT_CODE
    return FAILED_EXIT_CODE if summary.failed else 0
