"""The ``fleet-async`` command: run scenarios, sweep them, try the examples, replay traces,
serve a fleet to fleet software, benchmark.

``main`` parses the command line and hands it to the subcommand's module (``run``,
``sweep``, ``examples``, ``view``, ``serve``; ``bench`` is :mod:`fleet_async.bench`). A subcommand
reports a problem the user can fix by raising :class:`CliError`, which ``main`` prints as
``fleet-async: error: <message>`` (no traceback) with the error's exit code.

PyBullet's C code prints a build banner when it is imported and, in GUI mode, dozens of lines
when it connects and disconnects. Unless ``--verbose`` is given, ``main`` imports everything
that imports PyBullet, and runs the command, inside :func:`native_output_hidden`, which keeps
that output off the terminal; this module therefore imports no PyBullet-using module at the top.
"""

from __future__ import annotations

import argparse
import sys
import warnings
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
            (robots, sim time, steps, real-time factor, actions, collisions, fleet KPIs)
  sweep     run a scenario over a parameter grid and seeds, on a process pool or Ray, into
            one table of fleet KPIs (CSV or Parquet), optionally plotted
  examples  list the bundled examples (the default), run one, or copy them into a folder
  view      replay a trace (recorded with 'run --trace' or sim.start_trace) in the browser
            viewer: top-down, play / pause / speed / scrub, click a robot for its events
  serve     serve a scenario's robots as VDA 5050 vehicles over MQTT to your fleet
            software (a master control), paced at real time, until Ctrl-C
  bench     run the fleet-scale benchmark: step time, real-time factor, spawn time and
            memory per agent for fleets of N robots

'fleet-async COMMAND --help' explains every option of a command.
Every command keeps PyBullet's own C-level output (its build banner, GUI chatter) off the
terminal; --verbose shows it.
Exit codes: 0 success, 1 a sweep with failed runs, 2 bad input (options, scenario, missing
file), 130 interrupted; a Python example run by 'examples --run' exits with its own code.
"""

_RUN_EPILOG = """\
examples:
  fleet-async run examples/scenarios/pick_drop.yaml            # until its actions are done
  fleet-async run examples/scenarios/warehouse.yaml            # the shift its missions run
  fleet-async run my_scenario.yaml --duration 60 --record out.gif --record-size 400x300
  fleet-async run my_scenario.yaml --duration 30 --save-state warm.ckpt   # branch a sweep
  fleet-async run examples/scenarios/pick_drop.yaml --record out.gif --camera follow:robot0
  fleet-async run examples/scenarios/warehouse.yaml --trace warehouse.fatrace
  fleet-async run examples/scenarios/warehouse.yaml --view     # watch it live

How long a run lasts: --duration S if given, else the scenario's simulation.duration if it
sets one (> 0), else until the scenario's work is done: every mission it names has returned
and every robot has finished its actions: list and stopped; at most 600 s of sim time (the
summary says why the run stopped).

The summary explains each count: 'objects' is every sim object, robots included (as the
monitor counts them); 'robots' leaves out devices (doors, lifts, workcells), which are agents;
'actions completed' / 'actions failed' count the robots' ACTION_COMPLETED / ACTION_FAILED
events (cancelled actions count as failed); 'collisions' counts contacts that
began (a pair of objects that starts touching; touching again later counts again). The
counts from 'actions completed' to 'battery used' are the run's fleet KPIs (sim.kpis()), the
row 'fleet-async sweep' records for each run: tasks are TASK_COMPLETED / TASK_FAILED events
your code emits; times and distance are summed over the robots (and given per robot); a
robot's time is moving, waiting (standing with an action in progress) or idle. They count up
to the run's last step, so the actions that the end of a timed run cancels are not among them.
docs/sweeps.md defines each; --per-robot adds a table per robot. A progress bar is drawn on
stderr when it is a terminal.
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
        description="Build the simulation of SCENARIO.yaml as MultiRobotSimulationCore.from_yaml\n"
        "does, run its missions and actions, and print a summary.",
        epilog=_RUN_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        parents=[_common_options(argparse.SUPPRESS)],
    )
    run.add_arguments(parser)
    parser.set_defaults(handler=run.execute)


def _add_sweep(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from fleet_async.cli import sweep

    parser = subparsers.add_parser(
        "sweep",
        description="Run SCENARIO once per (grid point, seed): the grid is every combination "
        "of the\n--set values. Each run is one row of fleet KPIs in the --out table.",
        epilog=sweep.EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        parents=[_common_options(argparse.SUPPRESS)],
    )
    sweep.add_arguments(parser)
    parser.set_defaults(handler=sweep.execute)


def _add_examples(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from fleet_async.cli import examples

    parser = subparsers.add_parser(
        "examples",
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


def _add_view(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from fleet_async.cli import view

    parser = subparsers.add_parser(
        "view",
        description=_plain((view.__doc__ or "").strip()),
        epilog="examples:\n  fleet-async run examples/scenarios/warehouse.yaml --trace wh.fatrace\n"
        "  fleet-async view wh.fatrace\n  fleet-async view wh.fatrace --port 0 --no-browser",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        parents=[_common_options(argparse.SUPPRESS)],
    )
    view.add_arguments(parser)
    parser.set_defaults(handler=view.execute)


def _add_serve(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from fleet_async.cli import serve

    parser = subparsers.add_parser(
        "serve",
        description=_plain((serve.__doc__ or "").strip()),
        epilog=serve.EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        parents=[_common_options(argparse.SUPPRESS)],
    )
    serve.add_arguments(parser)
    parser.set_defaults(handler=serve.execute)


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
        description=_plain(doc),
        formatter_class=argparse.RawDescriptionHelpFormatter,
        parents=[_common_options(argparse.SUPPRESS)],
    )
    bench.add_arguments(parser)
    parser.set_defaults(handler=_run_bench)


def _plain(doc: str) -> str:
    """A docstring as terminal text: reST literals (double backticks) in single quotes."""
    return doc.replace("``", "'")


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
    # The commands are listed, with what each does, in the description above.
    subparsers = parser.add_subparsers(
        title="commands",
        dest="command",
        metavar="COMMAND",
        help="run, sweep, examples, view, serve or bench (see above)",
    )
    subparsers.required = True
    _add_run(subparsers)
    _add_sweep(subparsers)
    _add_examples(subparsers)
    _add_view(subparsers)
    _add_serve(subparsers)
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
    formatter = warnings.formatwarning
    if not _wants_verbose(arguments):  # a warning is one plain line, not a source listing
        warnings.formatwarning = _warning_line
    try:
        with native_output_hidden(enabled=not _wants_verbose(arguments)) as hidden:
            code = _main(arguments)
    finally:
        warnings.formatwarning = formatter
    if code != 0 and hidden.line_count:
        lines = f"{hidden.line_count} line{'s' if hidden.line_count != 1 else ''}"
        print(
            f"({lines} of PyBullet's own output hidden; add --verbose to see them)",
            file=sys.stderr,
        )
    return code


def _warning_line(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    line: str | None = None,
) -> str:
    return f"{PROG}: warning: {message}\n"


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
