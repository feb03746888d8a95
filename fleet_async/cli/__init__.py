"""The ``fleet-async`` command: run scenarios, try the examples, benchmark the simulator.

``main`` parses the command line and hands it to the subcommand's module (``run``,
``examples``; ``bench`` is :mod:`fleet_async.bench`). A subcommand reports a problem the user
can fix by raising :class:`CliError`, which ``main`` prints as ``fleet-async: error: <message>``
(no traceback) with the error's exit code.

PyBullet's C code prints a build banner when it is imported and, in GUI mode, dozens of lines
when it connects and disconnects. Unless ``--verbose`` is given, ``main`` imports everything
that imports PyBullet, and runs the command, inside :func:`native_output_hidden`, which keeps
that output off the terminal; this module therefore imports no PyBullet-using module at the top.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

import fleet_async
from fleet_async.cli.errors import CliError
from fleet_async.cli.native_output import native_output_hidden

__all__ = ["CliError", "build_parser", "main"]

PROG = "fleet-async"

_DESCRIPTION = """\
fleet_async: a kinematics-first multi-robot fleet simulator on PyBullet.

subcommands:
  run       build a scenario from its YAML file and run it headless, then print a summary
            (robots, sim time, steps, real-time factor, actions, collisions)
  examples  list the bundled examples (the default), run one, or copy them into a folder
  bench     run the fleet-scale benchmark: step time, real-time factor, spawn time and
            memory per agent for fleets of N robots

'fleet-async COMMAND --help' explains every option of a command.
Every command keeps PyBullet's own C-level output (its build banner, GUI chatter) off the
terminal; --verbose shows it.
Exit codes: 0 success, 2 bad input (options, scenario, missing file), 130 interrupted; a
Python example run by 'examples --run' exits with its own code.
"""

_RUN_EPILOG = """\
examples:
  fleet-async run examples/scenarios/pick_drop.yaml            # until its actions are done
  fleet-async run examples/scenarios/warehouse.yaml            # the shift its missions run
  fleet-async run my_scenario.yaml --duration 60 --record out.gif --record-size 400x300

How long a run lasts: --duration S if given, else the scenario's simulation.duration if it
sets one (> 0), else until the scenario's work is done: every mission it names has returned
and every robot has finished its actions: list and stopped; at most 600 s of sim time (the
summary says why the run stopped).

The summary explains each count: 'objects' is every sim object, robots included (as the
monitor counts them); 'actions completed' / 'actions failed' count ACTION_COMPLETED /
ACTION_FAILED events (cancelled actions count as failed); 'collisions' counts contacts that
began (a pair of objects that starts touching; touching again later counts again). A progress
bar is drawn on stderr when it is a terminal.
"""

_VERBOSE_HELP = "show PyBullet's own C-level output (build banner, GUI chatter), hidden by default"


def _common_options(default: object) -> argparse.ArgumentParser:
    """Options every command takes; ``default`` is SUPPRESS for the subcommands, so that a
    ``--verbose`` before the command is not reset by the subcommand's default."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--verbose", action="store_true", default=default, help=_VERBOSE_HELP)
    return parser


def _add_run(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from fleet_async.cli import run

    parser = subparsers.add_parser(
        "run",
        help="run a scenario YAML headless and print a summary",
        description="Build the simulation of SCENARIO.yaml as MultiRobotSimulationCore.from_yaml\n"
        "does, run its missions and actions, and print a summary.",
        epilog=_RUN_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        parents=[_common_options(argparse.SUPPRESS)],
    )
    run.add_arguments(parser)
    parser.set_defaults(handler=run.execute)


def _add_examples(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from fleet_async.cli import examples

    parser = subparsers.add_parser(
        "examples",
        help="list (the default), run or copy the examples",
        usage=examples.USAGE,
        description="The examples ship with fleet-async: Python scripts (*.py) and scenarios\n"
        "(scenarios/*.yaml), the same files as the source tree's examples/ folder.",
        epilog="examples:\n  fleet-async examples\n"
        "  fleet-async examples --run hello_fleet --max-steps 500\n"
        "  fleet-async examples --run pick_drop --rtf 0\n"
        "  fleet-async examples --copy my_examples",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        parents=[_common_options(argparse.SUPPRESS)],
    )
    examples.add_arguments(parser)
    parser.set_defaults(handler=examples.execute)


def _run_bench(args: argparse.Namespace) -> int:
    from fleet_async import bench

    try:
        return bench.run_from_args(args)
    except ValueError as exc:
        raise CliError(str(exc)) from exc


def _add_bench(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from fleet_async import bench

    doc = (bench.__doc__ or "").split("\n\nRun:")[0]
    parser = subparsers.add_parser(
        "bench",
        help="run the fleet-scale benchmark",
        description=doc,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        parents=[_common_options(argparse.SUPPRESS)],
    )
    bench.add_arguments(parser)
    parser.set_defaults(handler=_run_bench)


def build_parser() -> argparse.ArgumentParser:
    """The ``fleet-async`` argument parser with its subcommands (imports PyBullet)."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        parents=[_common_options(False)],
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
    _add_bench(subparsers)
    return parser


def _wants_verbose(argv: Sequence[str]) -> bool:
    """Whether ``--verbose`` is among the command's own options (before ``--run NAME ...``,
    whose arguments belong to the example)."""
    for arg in argv:
        if arg in ("--run", "--"):
            return False
        if arg == "--verbose":
            return True
    return False


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``fleet-async`` console script and of ``python -m fleet_async``.

    Args:
        argv: The arguments (without the program name); ``sys.argv[1:]`` if None.

    Returns:
        The exit code.
    """
    arguments = list(argv) if argv is not None else sys.argv[1:]
    with native_output_hidden(enabled=not _wants_verbose(arguments)) as hidden:
        code = _main(arguments)
    if code != 0 and hidden.line_count:
        lines = f"{hidden.line_count} line{'s' if hidden.line_count != 1 else ''}"
        print(
            f"({lines} of PyBullet's own output hidden; add --verbose to see them)",
            file=sys.stderr,
        )
    return code


def _main(arguments: list[str]) -> int:
    parser = build_parser()
    args = parser.parse_args(arguments)
    try:
        code: int = args.handler(args)
    except CliError as exc:
        sys.stdout.flush()
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    return code
