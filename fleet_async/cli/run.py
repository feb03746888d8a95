"""``fleet-async run SCENARIO.yaml``: build a scenario, run it, print what happened.

The scenario is loaded exactly as ``MultiRobotSimulationCore.from_yaml`` loads it, with two
settings decided by the command line instead of the file: ``gui`` (off unless ``--gui``) and,
when the scenario does not set ``target_rtf``, no real-time pacing (the library default of 1.0
is meant for interactive use; a command-line run goes as fast as it can). The run itself is
:func:`fleet_async.scenario_runner.run_scenario`: the scenario's missions and queued actions,
for ``--duration`` / ``simulation.duration`` or until its work is done (at most 600 s). The
summary includes the run's fleet KPIs (``sim.kpis()``, the row a sweep records per run), up to
the run's last step (``summary.py``). ``--camera`` picks what the GUI and ``--record`` look
at; ``--trace`` records a trace for ``fleet-async view`` and ``--view`` serves it live while
the run writes it (``live_view.py``).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fleet_async.cli import live_view
from fleet_async.cli.errors import CliError
from fleet_async.cli.progress import ProgressBar
from fleet_async.cli.summary import format_summary, summarize
from fleet_async.cli.tables import format_table
from fleet_async.core import CheckpointError, RobotKpis
from fleet_async.core.base.camera_config import parse_camera_mode
from fleet_async.core.base.config_utils import load_yaml_config
from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.params import SimulationParams
from fleet_async.core.base.steps import steps_for
from fleet_async.core.scenario.build import SCENARIO_SECTIONS
from fleet_async.core.simulation import MultiRobotSimulationCore
from fleet_async.core.view import gui, runner
from fleet_async.scenario_runner import DEFAULT_MAX_DURATION, ScenarioOutcome, run_scenario

if TYPE_CHECKING:
    pass

__all__ = [
    "StepWatcher",
    "add_arguments",
    "execute",
    "load_scenario",
    "run_steps",
    "steps_for",
]

INTERRUPTED_EXIT_CODE = 130
"""Exit code after Ctrl+C (128 + SIGINT), as shells report it."""


# ----- arguments ------------------------------------------------------------------------------


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def _non_negative_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def _frame_size(text: str) -> tuple[int, int]:
    width, sep, height = text.lower().partition("x")
    if not (sep and width.isdigit() and height.isdigit() and int(width) > 0 and int(height) > 0):
        raise argparse.ArgumentTypeError(
            f"expected WIDTHxHEIGHT in pixels (e.g. 640x480), got {text!r}"
        )
    return int(width), int(height)


def _positive_int(text: str) -> int:
    if not text.isdigit() or int(text) <= 0:
        raise argparse.ArgumentTypeError(f"expected a whole number > 0, got {text!r}")
    return int(text)


def _camera_mode(text: str) -> str:
    try:
        parse_camera_mode(text, "--camera")
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("--camera: ")) from None
    return text


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``run`` options to ``parser``."""
    parser.add_argument("scenario", metavar="SCENARIO.yaml", help="the scenario file to run")
    parser.add_argument(
        "--duration",
        type=_positive_float,
        metavar="S",
        help="sim seconds to run (the fewest whole steps covering it). Default: the "
        "scenario's simulation.duration; without one, until the scenario's missions have "
        f"returned and its actions are done, at most {DEFAULT_MAX_DURATION:g} s",
    )
    parser.add_argument(
        "--gui",
        action="store_true",
        help="open the PyBullet window (and the monitor window if the scenario enables "
        "'monitor'); SPACE pauses. Without it the run is headless whatever the scenario says",
    )
    parser.add_argument(
        "--rtf",
        type=_non_negative_float,
        metavar="X",
        help="pace the run at X sim seconds per wall second, 0 for as fast as possible "
        "(default: as fast as possible headless; with --gui, the scenario's target_rtf)",
    )
    parser.add_argument(
        "--record",
        metavar="OUT",
        help="record the run to OUT: .gif (needs Pillow) or .mp4 (needs imageio with PyAV); "
        'install both with: python -m pip install Pillow "imageio[pyav]"',
    )
    parser.add_argument(
        "--record-size",
        type=_frame_size,
        default=(800, 600),
        metavar="WxH",
        help="frame size of --record in pixels (default: 800x600; even numbers for .mp4)",
    )
    parser.add_argument(
        "--record-fps",
        type=_positive_int,
        default=15,
        metavar="N",
        help="frames per sim second of --record (default: 15; at most 50 for .gif)",
    )
    parser.add_argument(
        "--record-renderer",
        choices=("topdown", "pybullet"),
        default="topdown",
        help="how --record draws: topdown (the default: every body's footprint seen from "
        "above, framed on the robots and what they work with; many times faster) or pybullet "
        "(PyBullet's software renderer: perspective views, any --camera)",
    )
    parser.add_argument(
        "--backend",
        choices=("asyncio", "trio"),
        default="asyncio",
        help="the anyio event loop the scenario's missions run on (default: asyncio); the "
        "run is the same on both",
    )
    parser.add_argument(
        "--save-state",
        metavar="FILE",
        help="after the run, save a checkpoint of it to FILE (sim.save_state), to branch a "
        "sweep from: fleet-async sweep SCENARIO --checkpoint FILE",
    )
    parser.add_argument(
        "--per-robot",
        action="store_true",
        help="after the summary, print a table of each robot's figures (distance, moving / "
        "waiting / idle time, actions, tasks, collisions, battery)",
    )
    parser.add_argument(
        "--camera",
        type=_camera_mode,
        metavar="MODE",
        help="what the GUI window and --record look at (replaces the scenario's "
        "camera_config.camera_mode): auto (the whole scene, widening when a robot drives out "
        "of view; the default), top_down, orbit, fleet (follows the robots), follow:NAME "
        "(follows the body called NAME) or manual (camera_config's camera_distance / yaw / "
        "pitch / target)",
    )
    parser.add_argument(
        "--trace",
        metavar="OUT.fatrace",
        help="record a trace of the run (every body's pose per frame and the event log) for "
        "'fleet-async view'; replaces a 'trace:' section of the scenario",
    )
    parser.add_argument(
        "--trace-every",
        type=_positive_int,
        default=1,
        metavar="N",
        help="record a trace frame every N steps (default: 1, every step)",
    )
    parser.add_argument(
        "--view",
        action="store_true",
        help="watch the run live in the browser viewer (traces to --trace, or to "
        "SCENARIO.fatrace in the working directory), paced at the scenario's target_rtf or "
        "real time (1.0) unless --rtf says otherwise; after the run the page stays served "
        "until Ctrl+C",
    )
    parser.add_argument(
        "--view-port",
        type=int,
        default=8765,
        metavar="PORT",
        help="port of the --view page (default 8765; 0: any free port)",
    )
    parser.add_argument(
        "--quiet",
        action="store_true",
        help="print nothing (no progress bar, no summary, nothing the scenario's missions "
        "print); errors still go to stderr",
    )


# ----- loading --------------------------------------------------------------------------------


def load_scenario(
    path: Path,
    gui_on: bool,
    rtf: float | None,
    *,
    drop_trace: bool = False,
    live: bool = False,
) -> MultiRobotSimulationCore:
    """Build the simulation of the scenario file at ``path`` (as ``from_yaml`` does).

    Args:
        path: The scenario YAML (flat or nested layout).
        gui_on: Value for ``gui``, replacing the scenario's.
        rtf: Value for ``target_rtf``; None keeps the scenario's with a GUI (0 if it sets
            none) or a live view (1.0, real time, if it sets none: a run as fast as possible
            would end before a browser connects), and runs other headless runs as fast as
            possible.
        drop_trace: Ignore the scenario's ``trace:`` section (the command line traces).
        live: Someone watches the run as it happens (``--view``).

    Raises:
        FileNotFoundError, ValueError, TypeError: from the loader, naming the file and key.
    """
    config = load_yaml_config(path, allow_empty=False)
    if drop_trace and isinstance(config, dict):
        config.pop("trace", None)
    if any(key in SCENARIO_SECTIONS for key in config):
        if config.get("simulation") is None:
            config["simulation"] = {}
        settings = config["simulation"]
    else:
        settings = config
    # A malformed 'simulation:' section is left for the loader to report.
    if isinstance(settings, dict):
        # The command line overrides gui and target_rtf: check the file's values first, so a
        # wrong one is reported (field, value, file) rather than silently replaced.
        given = {key: settings[key] for key in ("gui", "target_rtf") if key in settings}
        SimulationParams.from_dict(given, source=str(path))
        settings["gui"] = gui_on
        if rtf is not None:
            settings["target_rtf"] = rtf
        elif live:
            if not settings.get("target_rtf"):  # unset or 0 (as fast as possible)
                settings["target_rtf"] = 1.0
        elif gui_on:
            settings.setdefault("target_rtf", 0.0)
        else:  # nobody is watching: pacing to the wall clock would only slow the run down
            settings["target_rtf"] = 0.0
    return MultiRobotSimulationCore.from_dict(config, source=str(path), base_dir=path.parent)


# ----- stepping -------------------------------------------------------------------------------


def run_steps(sim: MultiRobotSimulationCore, steps: int, on_frame: Callable[[], None]) -> int:
    """Run ``steps`` steps (paced at ``params.target_rtf`` when it is > 0), calling
    ``on_frame`` after every batch of steps.

    Returns:
        Steps run.

    Raises:
        CliError: if the simulation is paused without a GUI to resume it.
    """

    def frame() -> None:
        if sim.is_paused and not sim.is_gui:
            raise CliError(
                f"the simulation was paused at sim time {sim.sim_time:.3f} s (by a callback "
                "or plugin) and there is no GUI to resume it",
                exit_code=1,
            )
        on_frame()

    return runner.run_steps(sim, steps, frame)


# ----- the command ----------------------------------------------------------------------------


def execute(args: argparse.Namespace) -> int:
    """Run the ``run`` command; return the exit code."""
    path = Path(args.scenario)
    try:
        sim = load_scenario(
            path, args.gui, args.rtf, drop_trace=bool(args.trace or args.view), live=args.view
        )
    except (ValueError, TypeError, OSError) as exc:
        raise CliError(str(exc)) from exc
    try:
        return _run_loaded(sim, path, args)
    finally:
        sim.close()


def _set_camera(sim: MultiRobotSimulationCore, mode: str) -> None:
    """``--camera MODE``: the scenario's camera_config with ``camera_mode`` replaced."""
    sim.params.camera_config = {**(sim.params.camera_config or {}), "camera_mode": mode}
    try:
        sim.setup_camera()  # frames the GUI window; finds a follow:NAME body or says not
    except ValueError as exc:
        raise CliError(f"--camera {mode}: {exc}") from exc


def _start_recording(sim: MultiRobotSimulationCore, args: argparse.Namespace) -> None:
    width, height = args.record_size
    try:
        renderer = args.record_renderer
        if (
            renderer == "topdown"
            and args.camera
            and args.camera not in ("auto", "top_down", "fleet")
        ):
            renderer = "pybullet"  # a perspective camera was asked for: PyBullet draws it
        recorder = sim.start_recording(
            args.record, width=width, height=height, fps=args.record_fps, renderer=renderer
        )
    except (ImportError, ValueError) as exc:
        raise CliError(f"--record {args.record}: {exc}") from exc
    if not args.quiet and not sys.stderr.isatty():  # a terminal has the progress bar
        _report_recording(sim, recorder)


def _report_recording(sim: MultiRobotSimulationCore, recorder: Any, every: float = 5.0) -> None:
    """Where the bar cannot be drawn (a log, CI): a line on stderr every ``every`` wall s."""
    state = {"next": time.perf_counter() + every}

    def report(**_: Any) -> None:
        now = time.perf_counter()
        if now >= state["next"] and recorder.is_recording:
            state["next"] = now + every
            print(
                f"recording {recorder.output}: {recorder.frame_count} frames, "
                f"{sim.sim_time:.1f} s of sim time",
                file=sys.stderr,
                flush=True,
            )

    sim.events.on(SimEvents.POST_STEP, report, priority=101)  # after the recorder (100)


def _start_trace(sim: MultiRobotSimulationCore, path: Path, args: argparse.Namespace) -> None:
    out = args.trace or f"{path.stem}.fatrace"
    try:
        # A live page polls the file: write buffered frames four times a wall second.
        sim.start_trace(
            out, every_n_steps=args.trace_every, flush_seconds=0.25 if args.view else 1.0
        )
    except (OSError, ValueError) as exc:
        raise CliError(f"--trace {out}: {exc}") from exc


class StepWatcher:
    """After every step: the progress bar, GUI keys (SPACE pauses, here, until pressed again)
    and the monitor.

    Args:
        sim: The simulation; the watcher listens to its POST_STEP event.
        bar: The progress bar, or None.
        sleep: Wall-clock sleep while paused (injectable for tests).
    """

    def __init__(
        self,
        sim: MultiRobotSimulationCore,
        bar: ProgressBar | None,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        self._sim = sim
        self._bar = bar
        self._sleep = sleep
        self._start = sim.sim_time
        sim.events.on(SimEvents.POST_STEP, self._after_step)

    def _after_step(self, **_: Any) -> None:
        sim = self._sim
        if self._bar is not None:
            self._bar.update(sim.sim_time - self._start)
        if sim.is_gui:
            gui.handle_keyboard(sim)
            while sim.is_paused and sim.is_gui:  # missions wait in sim time: hold the clock
                self._sleep(1.0 / sim.params.gui_min_fps)
                gui.handle_keyboard(sim)
        sim.update_monitor()


def _shared_names_with_ids(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rows whose robot name is shared (Python allows that) say ``name#object_id``, as the
    trace viewer does."""
    counts: dict[Any, int] = {}
    for row in rows:
        counts[row["robot"]] = counts.get(row["robot"], 0) + 1
    return [
        {**row, "robot": f"{row['robot']}#{row['object_id']}"} if counts[row["robot"]] > 1 else row
        for row in rows
    ]


def _limit(sim: MultiRobotSimulationCore, requested: float | None) -> float | None:
    if requested is not None:
        return requested
    return float(sim.params.duration) if sim.params.duration > 0 else None


def _run_loaded(sim: MultiRobotSimulationCore, path: Path, args: argparse.Namespace) -> int:
    kpis = sim.kpis(from_now=True)
    if args.camera:
        _set_camera(sim, args.camera)
    if args.record:
        _start_recording(sim, args)
    if args.trace or args.view:
        _start_trace(sim, path, args)
    live = live_view.start(sim, args.view_port) if args.view else None
    if args.gui:
        sim.setup_monitor()
    limit = _limit(sim, args.duration)
    bar = (
        ProgressBar(limit or DEFAULT_MAX_DURATION, sys.stderr, open_ended=limit is None)
        if not args.quiet
        else None
    )
    StepWatcher(sim, bar)
    start_step, start_time = sim.step_count, sim.sim_time
    # At its limit the run cancels the missions still alive: the KPIs stop at its last step, as
    # a sweep's do, so the actions that ending cancels are not counted.
    kpis.stop_after_step(
        steps_for(start_time + (limit or DEFAULT_MAX_DURATION), sim.params.timestep)
    )
    outcome: ScenarioOutcome | None = None
    wall0 = time.perf_counter()
    streams = sys.stdout, sys.stderr
    if bar is not None and bar.enabled:
        bar.start()
        sys.stdout, sys.stderr = bar.guard(sys.stdout), bar.guard(sys.stderr)
    if args.quiet:  # what the missions print, too
        sys.stdout = io.StringIO()
    try:
        with contextlib.suppress(KeyboardInterrupt):  # Ctrl+C: summarise what ran
            outcome = run_scenario(sim, limit, backend=args.backend)
    finally:
        sys.stdout, sys.stderr = streams
    wall = time.perf_counter() - wall0
    if bar is not None:
        bar.finish(sim.sim_time - start_time)
    if args.record and not args.quiet:
        print(f"saving {args.record} ...", file=sys.stderr, flush=True)
    saved = sim.stop_recording() if args.record else None
    trace = sim.stop_trace()
    if args.save_state:
        try:
            sim.save_state(args.save_state)
        except CheckpointError as exc:
            raise CliError(str(exc)) from exc
    if not args.quiet:
        row = kpis.summary()
        print(
            format_summary(
                summarize(sim, row, sim.step_count - start_step, wall, outcome, saved, trace)
            )
        )
        if args.per_robot:
            robots = _shared_names_with_ids([r.as_dict() for r in kpis.per_robot()])
            print(f"\nper robot:\n{format_table(robots, RobotKpis.columns())}")
    if live is not None:
        live_view.serve_until_interrupted(live, keep=outcome is not None)
    return INTERRUPTED_EXIT_CODE if outcome is None else 0
