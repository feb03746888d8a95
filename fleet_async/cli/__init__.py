"""The ``fleet-async`` command: run scenarios, try the examples, benchmark the simulator.

``main`` parses the command line and hands it to the subcommand's module (``run``,
``examples``; ``bench`` is :mod:`fleet_async.bench`). A subcommand reports a problem the user
can fix by raising :class:`CliError`, which ``main`` prints as ``fleet-async: error: <message>``
(no traceback) with the error's exit code.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

import fleet_async
from fleet_async import bench
from fleet_async.cli import examples, run, view
from fleet_async.cli.errors import CliError

__all__ = ["CliError", "build_parser", "main"]

PROG = "fleet-async"

_DESCRIPTION = """\
fleet_async: a kinematics-first multi-robot fleet simulator on PyBullet.

subcommands:
  run       build a scenario from its YAML file and run it headless, then print a summary
            (robots, sim time, steps, real-time factor, actions, collisions)
  examples  list the bundled examples, run one, or copy them into a folder to edit
  view      replay a trace (recorded with 'run --trace' or sim.start_trace) in the browser
            viewer: top-down, play / pause / speed / scrub, click a robot for its events
  bench     run the fleet-scale benchmark: step time, real-time factor, spawn time and
            memory per agent for fleets of N robots

'fleet-async COMMAND --help' explains every option of a command.
Exit codes: 0 success, 2 bad input (options, scenario, missing file), 130 interrupted; a
Python example run by 'examples --run' exits with its own code.
"""

_RUN_EPILOG = """\
examples:
  fleet-async run examples/scenarios/pick_drop.yaml --duration 40
  fleet-async run my_scenario.yaml --duration 60 --record out.gif --record-size 400x300
  fleet-async run examples/scenarios/pick_drop.yaml --record out.gif --camera follow:robot0
  fleet-async run examples/scenarios/warehouse.yaml --trace warehouse.fatrace
  fleet-async run examples/scenarios/warehouse.yaml --view     # watch it live

The summary counts 'robots' (agents) and 'objects' (every other sim object), and
'actions completed' / 'actions failed' (ACTION_COMPLETED / ACTION_FAILED events; cancelled
actions count as failed). A progress bar is drawn on stderr when it is a terminal.
"""


def _add_run(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "run",
        help="run a scenario YAML headless and print a summary",
        description="Build the simulation of SCENARIO.yaml as MultiRobotSimulationCore.from_yaml\n"
        "does, step it for --duration sim seconds, and print a summary.",
        epilog=_RUN_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    run.add_arguments(parser)
    parser.set_defaults(handler=run.execute)


def _add_examples(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "examples",
        help="list, run or copy the examples",
        usage=examples.USAGE,
        description="The examples are the source tree's examples/ folder: Python scripts\n"
        "(examples/*.py) and scenarios (examples/scenarios/*.yaml).",
        epilog="examples:\n  fleet-async examples --list\n"
        "  fleet-async examples --run hello_fleet --max-steps 500\n"
        "  fleet-async examples --run pick_drop --duration 40 --rtf 0\n"
        "  fleet-async examples --copy my_examples",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    examples.add_arguments(parser)
    parser.set_defaults(handler=examples.execute)


def _add_view(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "view",
        help="replay a trace in the browser viewer",
        description=(view.__doc__ or "").strip(),
        epilog="examples:\n  fleet-async run examples/scenarios/warehouse.yaml --trace wh.fatrace\n"
        "  fleet-async view wh.fatrace\n  fleet-async view wh.fatrace --port 0 --no-browser",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    view.add_arguments(parser)
    parser.set_defaults(handler=view.execute)


def _run_bench(args: argparse.Namespace) -> int:
    try:
        return bench.run_from_args(args)
    except ValueError as exc:
        raise CliError(str(exc)) from exc


def _add_bench(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    doc = (bench.__doc__ or "").split("\n\nRun:")[0]
    parser = subparsers.add_parser(
        "bench",
        help="run the fleet-scale benchmark",
        description=doc,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    bench.add_arguments(parser)
    parser.set_defaults(handler=_run_bench)


def build_parser() -> argparse.ArgumentParser:
    """The ``fleet-async`` argument parser with its subcommands."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--version",
        action="version",
        version=f"%(prog)s {fleet_async.__version__}",
        help="print the version and exit",
    )
    subparsers = parser.add_subparsers(title="commands", dest="command", metavar="COMMAND")
    subparsers.required = True
    _add_run(subparsers)
    _add_examples(subparsers)
    _add_view(subparsers)
    _add_bench(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``fleet-async`` console script.

    Args:
        argv: The arguments (without the program name); ``sys.argv[1:]`` if None.

    Returns:
        The exit code.
    """
    parser = build_parser()
    args = parser.parse_args(list(argv) if argv is not None else None)
    try:
        code: int = args.handler(args)
    except CliError as exc:
        sys.stdout.flush()
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    return code
