"""``fleet-async run SCENARIO.yaml``: build a scenario, step it, print what happened.

The scenario is loaded exactly as ``MultiRobotSimulationCore.from_yaml`` loads it, with two
settings decided by the command line instead of the file: ``gui`` (off unless ``--gui``) and,
when the scenario does not set ``target_rtf``, no real-time pacing (the library default of 1.0
is meant for interactive use; a command-line run goes as fast as it can).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fleet_async.cli import live_view
from fleet_async.cli.errors import CliError
from fleet_async.cli.progress import ProgressBar
from fleet_async.core.base.config_utils import load_yaml_config
from fleet_async.core.base.events import SimEvents
from fleet_async.core.scenario.build import SCENARIO_SECTIONS
from fleet_async.core.sim.camera_config import parse_camera_mode
from fleet_async.core.simulation import MultiRobotSimulationCore
from fleet_async.core.view import gui, runner
from fleet_async.core.view.runner import steps_for

__all__ = [
    "ActionTally",
    "RunSummary",
    "add_arguments",
    "execute",
    "format_summary",
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
        help="sim seconds to run (default: the scenario's simulation.duration; required when "
        "that is not set or <= 0); the run takes the fewest whole steps covering it",
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
        'install both with: pip install "fleet-async[record]"',
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
        "SCENARIO.fatrace in the working directory); after the run the page stays served "
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
        help="print nothing (no progress bar, no summary); errors still go to stderr",
    )


# ----- loading --------------------------------------------------------------------------------


def load_scenario(
    path: Path, gui_on: bool, rtf: float | None, *, drop_trace: bool = False
) -> MultiRobotSimulationCore:
    """Build the simulation of the scenario file at ``path`` (as ``from_yaml`` does).

    Args:
        path: The scenario YAML (flat or nested layout).
        gui_on: Value for ``gui``, replacing the scenario's.
        rtf: Value for ``target_rtf``; None keeps the scenario's with a GUI (0 if it sets
            none) and runs headless runs as fast as possible.
        drop_trace: Ignore the scenario's ``trace:`` section (the command line traces).

    Raises:
        FileNotFoundError, ValueError, TypeError: from the loader, naming the file and key.
    """
    config = load_yaml_config(path)
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
        settings["gui"] = gui_on
        if rtf is not None:
            settings["target_rtf"] = rtf
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


class ActionTally:
    """Counts ``ACTION_COMPLETED`` and ``ACTION_FAILED`` events of a simulation."""

    def __init__(self, sim: MultiRobotSimulationCore) -> None:
        self.completed = 0
        self.failed = 0
        sim.events.on(SimEvents.ACTION_COMPLETED, self._on_completed)
        sim.events.on(SimEvents.ACTION_FAILED, self._on_failed)

    def _on_completed(self, **_: Any) -> None:
        self.completed += 1

    def _on_failed(self, **_: Any) -> None:
        self.failed += 1


# ----- the summary ----------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class RunSummary:
    """What one run did.

    Attributes:
        robots: Agents in the simulation at the end.
        objects: Other sim objects at the end (not counting robots).
        sim_time: Sim seconds at the end.
        steps: Steps this run took.
        wall_time: Wall seconds spent stepping (loading not included).
        actions_completed: ``ACTION_COMPLETED`` events during the run.
        actions_failed: ``ACTION_FAILED`` events (failed or cancelled actions).
        collisions: ``sim.collision_count`` at the end.
        recording: The saved recording, if any.
        trace: The saved trace, if any.
        interrupted: Whether Ctrl+C stopped the run early.
    """

    robots: int
    objects: int
    sim_time: float
    steps: int
    wall_time: float
    actions_completed: int
    actions_failed: int
    collisions: int
    recording: str | None = None
    interrupted: bool = False
    trace: str | None = None

    @property
    def real_time_factor(self) -> float:
        """Sim seconds run per wall second (``inf`` if no wall time was measured)."""
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf


def format_summary(summary: RunSummary) -> str:
    """The summary as aligned ``name: value`` lines."""
    rtf = summary.real_time_factor
    rows = [
        ("robots", str(summary.robots)),
        ("objects", f"{summary.objects} (not counting robots)"),
        ("sim time", f"{summary.sim_time:.3f} s"),
        ("steps", str(summary.steps)),
        ("wall time", f"{summary.wall_time:.3f} s"),
        ("real-time factor", f"{rtf:.1f}x" if math.isfinite(rtf) else "inf"),
        ("actions completed", str(summary.actions_completed)),
        ("actions failed", str(summary.actions_failed)),
        ("collisions", str(summary.collisions)),
    ]
    if summary.recording is not None:
        rows.append(("recording", summary.recording))
    if summary.trace is not None:
        rows.append(("trace", summary.trace))
    if summary.interrupted:
        rows.append(("interrupted", "yes (Ctrl+C)"))
    return "\n".join(f"{name + ':':<19}{value}" for name, value in rows)


# ----- the command ----------------------------------------------------------------------------


def execute(args: argparse.Namespace) -> int:
    """Run the ``run`` command; return the exit code."""
    path = Path(args.scenario)
    try:
        sim = load_scenario(path, args.gui, args.rtf, drop_trace=bool(args.trace or args.view))
    except (ValueError, TypeError, OSError) as exc:
        raise CliError(str(exc)) from exc
    try:
        return _run_loaded(sim, path, args)
    finally:
        sim.close()


def _duration(sim: MultiRobotSimulationCore, path: Path, requested: float | None) -> float:
    if requested is not None:
        return requested
    duration = sim.params.duration
    if duration <= 0:
        raise CliError(
            f"{path}: the scenario sets no run length (simulation.duration = {duration}); "
            "give one with --duration SECONDS"
        )
    return duration


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
        sim.start_recording(args.record, width=width, height=height, fps=args.record_fps)
    except (ImportError, ValueError) as exc:
        raise CliError(f"--record {args.record}: {exc}") from exc


def _start_trace(sim: MultiRobotSimulationCore, path: Path, args: argparse.Namespace) -> None:
    out = args.trace or f"{path.stem}.fatrace"
    try:
        # A live page polls the file: write buffered frames four times a wall second.
        sim.start_trace(
            out, every_n_steps=args.trace_every, flush_seconds=0.25 if args.view else 1.0
        )
    except (OSError, ValueError) as exc:
        raise CliError(f"--trace {out}: {exc}") from exc


def _run_loaded(sim: MultiRobotSimulationCore, path: Path, args: argparse.Namespace) -> int:
    duration = _duration(sim, path, args.duration)
    tally = ActionTally(sim)
    if args.camera:
        _set_camera(sim, args.camera)
    if args.record:
        _start_recording(sim, args)
    if args.trace or args.view:
        _start_trace(sim, path, args)
    live = live_view.start(sim, args.view_port) if args.view else None
    if args.gui:
        sim.setup_monitor()
    bar = ProgressBar(duration, sys.stderr) if not args.quiet else None
    sim_start = sim.sim_time

    def on_frame() -> None:
        if sim.is_gui:
            gui.handle_keyboard(sim)
        if bar is not None:
            bar.update(sim.sim_time - sim_start)

    start_step, interrupted = sim.step_count, False
    wall0 = time.perf_counter()
    if bar is not None:
        bar.start()
    try:
        run_steps(sim, steps_for(duration, sim.params.timestep), on_frame)
    except KeyboardInterrupt:
        interrupted = True
    wall = time.perf_counter() - wall0
    if bar is not None:
        bar.finish(sim.sim_time - sim_start)
    saved = sim.stop_recording() if args.record else None
    trace = sim.stop_trace()
    if not args.quiet:
        steps = sim.step_count - start_step
        summary = _summarize(sim, tally, steps, wall, saved, interrupted)
        print(format_summary(dataclasses.replace(summary, trace=trace)))
    if live is not None:
        live_view.serve_until_interrupted(live, keep=not interrupted)
    return INTERRUPTED_EXIT_CODE if interrupted else 0


def _summarize(
    sim: MultiRobotSimulationCore,
    tally: ActionTally,
    steps: int,
    wall: float,
    recording: str | None,
    interrupted: bool,
) -> RunSummary:
    robots = len(sim.agents)
    return RunSummary(
        robots=robots,
        objects=len(sim.sim_objects) - robots,
        sim_time=sim.sim_time,
        steps=steps,
        wall_time=wall,
        actions_completed=tally.completed,
        actions_failed=tally.failed,
        collisions=sim.collision_count,
        recording=recording,
        interrupted=interrupted,
    )
