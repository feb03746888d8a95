"""The fleet-async command: the installed console script end to end, its pieces in process."""

from __future__ import annotations

import dataclasses
import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import urllib.request
from pathlib import Path

import pytest
from PIL import Image

import fleet_async
from fleet_async import FleetKpis
from fleet_async.cli import main
from fleet_async.cli.errors import CliError
from fleet_async.cli.progress import ProgressBar, format_progress
from fleet_async.cli.run import load_scenario, run_steps, steps_for
from fleet_async.cli.summary import RunSummary, format_summary
from fleet_async.viewer import TraceReader

REPO = Path(__file__).resolve().parent.parent

# Two robots that each drive 1 m and wait 0.5 s, and one box; 10 s of sim time by default.
SCENARIO = """\
# A tiny test scenario.
simulation:
  gui: true
  monitor: false
  timestep: 0.1
  duration: 10.0
entities:
  - {type: sim_object, name: box, pose: [0.0, 3.0, 0.1],
     visual_shape: {shape_type: box, half_extents: [0.1, 0.1, 0.1]},
     collision_shape: {shape_type: box, half_extents: [0.1, 0.1, 0.1]}}
  - name: r0
    urdf_path: simple_cube
    pose: [0.0, 0.0, 0.1]
    controller: {type: omni, max_linear_vel: 1.0}
    actions:
      - {type: move, path: [[1.0, 0.0, 0.1]]}
      - {type: wait, duration: 0.5}
  - name: r1
    urdf_path: simple_cube
    pose: [0.0, -2.0, 0.1]
    controller: {type: omni, max_linear_vel: 1.0}
    actions:
      - {type: move, path: [[1.0, -2.0, 0.1]]}
      - {type: wait, duration: 0.5}
"""


@pytest.fixture(scope="module")
def script() -> str:
    """The installed console script; its absence is a failure, not a skip."""
    path = shutil.which("fleet-async")
    assert path is not None, 'fleet-async is not installed: pip install -e ".[test]"'
    return path


@pytest.fixture
def scenario(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.yaml"
    path.write_text(SCENARIO)
    return path


def cli(
    script: str, *args: str | Path, cwd: Path | None = None, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """Run the console script headless (no display) and capture its output."""
    base = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    return subprocess.run(
        [script, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=cwd,
        env={**base, **(env or {})},
        check=False,
    )


def summary_of(stdout: str) -> dict[str, str]:
    """``name: value`` lines of the run summary, without the explanations in brackets."""
    pairs = (line.split(":", 1) for line in stdout.splitlines() if ":" in line)
    return {name.strip(): value.split(" (", 1)[0].strip() for name, value in pairs}


def error_line(stderr: str) -> str:
    """The ``fleet-async: error:`` line (pybullet prints its build time on stderr too)."""
    lines = [line for line in stderr.splitlines() if line.startswith("fleet-async: error: ")]
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr
    return lines[0]


# ----- help -----------------------------------------------------------------------------------


def test_help_names_every_subcommand(script):
    result = cli(script, "--help")
    assert result.returncode == 0, result.stderr
    for command in ("run", "sweep", "examples", "view", "bench"):
        assert f"\n  {command} " in result.stdout


@pytest.mark.parametrize(
    ("command", "options"),
    [
        (
            "run",
            [
                "--duration",
                "--gui",
                "--rtf",
                "--record",
                "--record-size",
                "--per-robot",
                "--camera",
                "--quiet",
                "--trace",
                "--view",
            ],
        ),
        (
            "sweep",
            ["--seeds", "--set", "--out", "--engine", "--address", "--workers", "--plot", "--keys"],
        ),
        ("view", ["--port", "--host", "--no-browser", "--follow"]),
        ("examples", ["--list", "--run", "--copy"]),
        ("bench", ["--n", "--large", "--json", "--profile"]),
    ],
)
def test_each_subcommand_explains_its_options(command, options, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([command, "--help"])
    assert exit_info.value.code == 0
    out = capsys.readouterr().out
    for option in options:
        assert f"  {option} " in out, option


@pytest.mark.parametrize("module", ["fleet_async", "fleet_async.cli"])
def test_python_dash_m_runs_the_same_command(module):
    result = subprocess.run(
        [sys.executable, "-m", module, "--version"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"fleet-async {fleet_async.__version__}"


def test_pybullet_output_is_hidden_unless_verbose(script, scenario):
    quiet = cli(script, "run", scenario, "--duration", "1")
    assert quiet.returncode == 0, quiet.stderr
    assert "pybullet build time" not in quiet.stdout + quiet.stderr
    assert summary_of(quiet.stdout)["steps"] == "10"
    for argv in (["--verbose", "run", scenario], ["run", scenario, "--verbose"]):
        loud = cli(script, *argv, "--duration", "1")
        assert loud.returncode == 0, loud.stderr
        assert "pybullet build time" in loud.stdout + loud.stderr
        assert summary_of(loud.stdout)["steps"] == "10"


def test_importing_the_command_line_does_not_import_pybullet():
    code = "import sys, fleet_async.cli; print('pybullet' in sys.modules)"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False
    )
    assert result.stdout.strip() == "False", result.stdout + result.stderr


# ----- run ------------------------------------------------------------------------------------


def test_run_prints_the_summary(script, scenario):
    result = cli(script, "run", scenario)
    assert result.returncode == 0, result.stderr
    summary = summary_of(result.stdout)
    assert summary["robots"] == "2"
    assert summary["objects"] == "3"  # robots included, as the monitor counts
    assert summary["sim time"] == "10.000 s"
    assert summary["steps"] == "100"
    assert summary["actions completed"] == "4"
    assert summary["actions failed"] == "0"
    assert summary["collisions"] == "0"
    assert summary["stopped"] == "the duration of 10 s was reached"
    assert "recording" not in summary
    # Each count says what it counts.
    assert "collisions:        0 (contacts that began" in result.stdout
    assert "objects:           3 (every sim object, robots included)" in result.stdout


def test_run_prints_the_fleet_kpis_in_the_summary_and_per_robot_detail(script, scenario):
    result = cli(script, "run", scenario, "--per-robot")
    assert result.returncode == 0, result.stderr
    block, table = result.stdout.split("\n\nper robot:\n")
    # One block: every line is 'name: value', the KPIs among the run's figures.
    assert all(": " in line for line in block.splitlines()), block
    summary = summary_of(block)
    assert (summary["robots"], summary["steps"], summary["actions completed"]) == ("2", "100", "4")
    assert summary["distance"] == "2.0 m" and summary["tasks completed"] == "0"
    assert summary["battery used"] == "-"  # no robot has a battery
    assert "distance:          2.0 m (driven, summed over 2 robots; 1.0 m per robot)" in block
    rows = table.splitlines()
    assert rows[0].split()[:3] == ["robot", "object_id", "distance_m"]
    assert [line.split()[0] for line in rows[1:]] == ["r0", "r1"]


def test_run_duration_option_overrides_the_scenario(script, scenario):
    result = cli(script, "run", scenario, "--duration", "0.25")
    assert result.returncode == 0, result.stderr
    summary = summary_of(result.stdout)
    assert (summary["steps"], summary["sim time"]) == ("3", "0.300 s")
    assert summary["actions completed"] == "0"


def test_run_quiet_prints_nothing(script, scenario):
    result = cli(script, "run", scenario, "--duration", "1", "--quiet")
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""


def test_run_quiet_silences_the_missions_too(script):
    # The warehouse's missions print a mission log; --quiet prints nothing at all.
    warehouse = REPO / "examples" / "scenarios" / "warehouse.yaml"
    result = cli(script, "run", warehouse, "--duration", "10", "--quiet")
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""


def test_view_runs_live_at_real_time_unless_told(tmp_path):
    from fleet_async.cli.run import load_scenario

    path = tmp_path / "s.yaml"
    path.write_text("simulation: {gui: false}\nentities: []\n")
    for rtf, expected in ((None, 1.0), (0.0, 0.0), (5.0, 5.0)):
        with load_scenario(path, gui_on=False, rtf=rtf, live=True) as sim:
            assert sim.params.target_rtf == expected
    path.write_text("simulation: {gui: false, target_rtf: 3}\nentities: []\n")
    with load_scenario(path, gui_on=False, rtf=None, live=True) as sim:
        assert sim.params.target_rtf == 3.0


def test_run_records_a_gif(script, scenario, tmp_path):
    out = tmp_path / "clips" / "run.gif"
    result = cli(
        script,
        "run",
        scenario,
        "--duration",
        "1",
        "--record",
        out,
        "--record-size",
        "64x48",
        "--record-fps",
        "5",
    )
    assert result.returncode == 0, result.stderr
    assert summary_of(result.stdout)["recording"] == str(out)
    with Image.open(out) as image:
        assert (image.format, image.size) == ("GIF", (64, 48))
        assert image.n_frames >= 2


def test_run_camera_follows_a_robot_in_the_recording(script, scenario, tmp_path):
    out = tmp_path / "follow.gif"
    args = ["--duration", "1", "--record", out, "--record-size", "64x48", "--quiet"]
    result = cli(script, "run", scenario, *args, "--camera", "follow:r1")
    assert result.returncode == 0, result.stderr
    assert out.exists()


@pytest.mark.parametrize(
    ("mode", "message"),
    [
        ("fisheye", r"--camera: .*got 'fisheye'"),
        ("follow:nobody", r"--camera follow:nobody: .*no body called 'nobody'.*r0"),
    ],
)
def test_run_bad_camera_names_the_option_and_value(script, scenario, mode, message):
    result = cli(script, "run", scenario, "--duration", "1", "--camera", mode)
    assert result.returncode == 2
    assert re.search(message, result.stderr), result.stderr


def test_run_record_without_pillow_explains_what_to_install(script, scenario, tmp_path):
    shadow = tmp_path / "shadow" / "PIL"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text("raise ImportError('Pillow hidden by the test')\n")
    result = cli(
        script,
        "run",
        scenario,
        "--duration",
        "1",
        "--record",
        tmp_path / "out.gif",
        env={"PYTHONPATH": os.pathsep.join([str(shadow.parent), os.environ.get("PYTHONPATH", "")])},
    )
    assert result.returncode == 2
    line = error_line(result.stderr)
    assert "needs Pillow" in line
    assert 'python -m pip install Pillow "imageio[pyav]"' in line
    assert not (tmp_path / "out.gif").exists()


def test_run_bad_key_names_key_and_file(script, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("simulation:\n  timestep: 0.1\n  tiemstep: 0.2\n")
    result = cli(script, "run", bad, "--duration", "1")
    assert result.returncode == 2
    line = error_line(result.stderr)
    assert str(bad) in line
    assert "'tiemstep'" in line
    assert result.stdout == ""


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("gui: maybe", "simulation.gui: expected bool, got 'maybe'"),
        ("target_rtf: [1]", "simulation.target_rtf"),
    ],
)
def test_run_bad_gui_or_rtf_in_the_file_is_reported_not_overridden(script, tmp_path, line, message):
    # The command line sets gui and target_rtf itself; the file's wrong value is still an error.
    bad = tmp_path / "bad.yaml"
    bad.write_text(f"simulation:\n  timestep: 0.1\n  {line}\n")
    result = cli(script, "run", bad, "--duration", "1")
    assert result.returncode == 2
    assert str(bad) in error_line(result.stderr) and message in error_line(result.stderr)


def test_run_missing_file_is_an_error(script, tmp_path):
    result = cli(script, "run", tmp_path / "nope.yaml")
    assert result.returncode == 2
    assert str(tmp_path / "nope.yaml") in error_line(result.stderr)


@pytest.mark.parametrize("text", ["", "# nothing but a comment\n"])
def test_run_of_an_empty_scenario_file_is_an_error(tmp_path, text):
    path = tmp_path / "empty.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))}: the file is empty"):
        load_scenario(path, gui_on=False, rtf=0)


def test_run_without_a_duration_runs_until_the_actions_are_done(script, tmp_path):
    path = tmp_path / "until_done.yaml"
    path.write_text(SCENARIO.replace("  duration: 10.0\n", ""))
    result = cli(script, "run", path)
    assert result.returncode == 0, result.stderr
    summary = summary_of(result.stdout)
    # 1 m at 1 m/s with acceleration limits, then a 0.5 s wait: done at the step it ends.
    assert summary["actions completed"] == "4"
    assert summary["stopped"] == "its work is done"
    assert float(summary["sim time"].split()[0]) < 5.0


def test_run_without_a_duration_or_work_stops_at_the_cap(script, tmp_path):
    path = tmp_path / "forever.yaml"
    path.write_text("simulation:\n  timestep: 0.5\n")
    result = cli(script, "run", path)
    assert result.returncode == 0, result.stderr
    summary = summary_of(result.stdout)
    assert (summary["sim time"], summary["steps"]) == ("600.000 s", "1200")
    assert "no missions, no actions and no duration" in result.stdout


def test_load_scenario_is_unpaced_headless_unless_asked(tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    plain = tmp_path / "plain.yaml"
    plain.write_text("simulation: {gui: true, monitor: false}\n")
    paced = tmp_path / "paced.yaml"
    paced.write_text("simulation: {gui: true, monitor: false, target_rtf: 2.5}\n")
    flat = tmp_path / "flat.yaml"
    flat.write_text("gui: true\nmonitor: false\ntimestep: 0.05\n")
    cases = [(plain, None, 0.0), (paced, None, 0.0), (paced, 0.0, 0.0), (flat, 4.0, 4.0)]
    for path, rtf, expected in cases:
        sim = load_scenario(path, gui_on=False, rtf=rtf)
        try:
            assert (sim.is_gui, sim.params.gui, sim.params.target_rtf) == (False, False, expected)
        finally:
            sim.close()
    # With --gui the scenario's own pacing is kept (headless here: GUI falls back to DIRECT).
    with pytest.warns(RuntimeWarning, match="no display"):
        sim = load_scenario(paced, gui_on=True, rtf=None)
    try:
        assert (sim.params.gui, sim.params.target_rtf) == (True, 2.5)
    finally:
        sim.close()


def test_steps_for_covers_the_duration_with_whole_steps():
    assert steps_for(0.3, 0.1) == 3
    assert steps_for(0.25, 0.1) == 3
    assert steps_for(10.0, 0.1) == 100


def test_run_steps_refuses_a_headless_pause(sim):
    sim.step_once()
    sim.pause()
    with pytest.raises(CliError, match=r"paused at sim time 0\.100 s") as info:
        run_steps(sim, 5, lambda: None)
    assert info.value.exit_code == 1
    assert sim.step_count == 1


def test_run_steps_steps_exactly_and_reports_each_frame(sim):
    frames = []
    assert run_steps(sim, 25, lambda: frames.append(sim.step_count)) == 25
    # Unpaced, frames come every max_steps_per_frame (10) steps, the last one short.
    assert frames == [10, 20, 25]


def test_summary_lines():
    summary = RunSummary(
        2, 3, 10.0, 100, 0.5, 4, 1, 3, missions=1, stopped="why", recording="out.gif"
    )
    assert format_summary(summary).splitlines() == [
        "robots:            2 (agents)",
        "objects:           3 (every sim object, robots included)",
        "sim time:          10.000 s",
        "steps:             100",
        "wall time:         0.500 s",
        "real-time factor:  20.0x",
        "missions:          1 (the scenario's missions: entries)",
        "actions completed: 4",
        "actions failed:    1 (failed or cancelled)",
        "collisions:        3 (contacts that began: each time two objects started to touch)",
        "stopped:           why",
        "recording:         out.gif",
    ]


KPIS = FleetKpis(
    robot_count=3, steps=100, sim_time_s=10.0, tasks_completed=2, tasks_failed=1,
    throughput_per_hour=720.0, actions_completed=4, actions_failed=2, actions_cancelled=1,
    distance_total_m=6.0, distance_mean_m=2.0, moving_time_total_s=12.0,
    moving_time_mean_s=4.0, waiting_time_total_s=9.0, waiting_time_mean_s=3.0,
    idle_time_total_s=9.0, idle_time_mean_s=3.0, collisions=3, mission_errors=0,
    battery_robots=2, battery_used_total=0.5, battery_used_mean=0.25, battery_min_soc=0.7,
)  # fmt: skip


def test_summary_lines_with_the_fleet_kpis():
    summary = RunSummary(2, 3, 10.0, 100, 0.5, 4, 2, 3, missions=1, stopped="why", kpis=KPIS)
    assert format_summary(summary).splitlines() == [
        "robots:            2 (agents at the end; the figures below count 3, those removed "
        "during the run too)",
        "objects:           3 (every sim object, robots included)",
        "sim time:          10.000 s",
        "steps:             100",
        "wall time:         0.500 s",
        "real-time factor:  20.0x",
        "missions:          1 (the scenario's missions: entries)",
        "actions completed: 4",
        "actions failed:    2 (failed or cancelled; 1 of them cancelled)",
        "collisions:        3 (contacts that began: each time two objects started to touch)",
        "tasks completed:   2 (TASK_COMPLETED events: work reported done)",
        "tasks failed:      1 (TASK_FAILED events)",
        "throughput:        720.0 tasks completed per hour of sim time",
        "distance:          6.0 m (driven, summed over 3 robots; 2.0 m per robot)",
        "moving time:       12.0 s (summed over 3 robots; 4.0 s per robot)",
        "waiting time:      9.0 s (standing with an action in progress, summed over 3 robots; "
        "3.0 s per robot)",
        "idle time:         9.0 s (standing with no action, summed over 3 robots; 3.0 s per robot)",
        "mission errors:    0 (exceptions that ended a mission)",
        "battery used:      0.500 full batteries (summed over 2 robots with one; 0.250 per "
        "robot; lowest charge left 0.70)",
        "stopped:           why",
    ]


def test_summary_robots_leave_out_devices():
    summary = RunSummary(2, 9, 10.0, 100, 0.5, 4, 1, 3, devices=3)
    assert format_summary(summary).splitlines()[0] == (
        "robots:            2 (agents; 3 more are devices, not robots)"
    )
    one_removed = dataclasses.replace(summary, kpis=dataclasses.replace(KPIS, robot_count=3))
    assert format_summary(one_removed).splitlines()[0] == (
        "robots:            2 (agents at the end; the figures below count 3, those removed "
        "during the run too; 3 more are devices, not robots)"
    )


# ----- the progress bar -----------------------------------------------------------------------


class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_bar_redraws_at_most_every_interval_on_a_terminal():
    now = [0.0]
    stream = FakeTerminal()
    bar = ProgressBar(10.0, stream, min_interval=0.1, clock=lambda: now[0])
    bar.start()
    now[0] = 0.05
    assert bar.update(1.0) is False
    now[0] = 0.2
    assert bar.update(2.0) is True
    now[0] = 0.25
    assert bar.update(2.5) is False
    now[0] = 1.0
    bar.finish(10.0)
    assert stream.getvalue() == (
        "\r[####....................]  2.0/10.0 s   20%  RTF 10.0x"
        "\r[########################]  10.0/10.0 s  100%  RTF 10.0x\n"
    )


def test_progress_bar_pads_over_a_longer_previous_line():
    now = [0.0]
    stream = FakeTerminal()
    bar = ProgressBar(100.0, stream, min_interval=0.1, clock=lambda: now[0])
    now[0] = 0.1
    bar.update(100.0)  # RTF 1000.0x
    now[0] = 100.0
    bar.update(100.0)  # RTF 1.0x: three characters shorter
    first, second = stream.getvalue().split("\r")[1:]
    assert len(second) == len(first)
    assert second.endswith("RTF 1.0x   ")


def test_progress_bar_draws_nothing_when_not_a_terminal():
    now = [0.0]
    stream = io.StringIO()
    bar = ProgressBar(10.0, stream, clock=lambda: now[0])
    for step in range(1, 11):
        now[0] = float(step)
        assert bar.update(float(step)) is False
    bar.finish(10.0)
    assert stream.getvalue() == ""


def test_format_progress_of_a_run_until_done_has_no_percentage():
    line = format_progress(26.7, 600.0, 34.12, open_ended=True)
    assert line == "running until done: 26.7 s (at most 600 s)  RTF 34.1x"


def test_format_progress_clamps_and_handles_no_wall_time():
    assert format_progress(0.0, 4.0, float("inf"), width=4) == "[....]  0.0/4.0 s    0%  RTF -"
    assert format_progress(5.0, 4.0, 2.0, width=4) == "[####]  5.0/4.0 s  100%  RTF 2.0x"


# ----- examples -------------------------------------------------------------------------------


@pytest.mark.parametrize("flags", [[], ["--list"]])
def test_examples_list_names_scripts_and_scenarios(script, flags):
    result = cli(script, "examples", *flags)
    assert result.returncode == 0, result.stderr
    rows = {line.split()[0]: line for line in result.stdout.splitlines() if line.startswith("  ")}
    assert "Hello, fleet: four robots carry pallets" in rows["hello_fleet"]
    assert "Three robots each fetch a box" in rows["pick_drop"]
    assert f"(from {REPO / 'examples'})" in result.stdout


def test_examples_run_passes_arguments_and_exit_code_through(script):
    done = cli(script, "examples", "--run", "hello_fleet", "--max-steps", "300")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "4/4 pallets delivered" in done.stdout
    # 50 steps are too few to deliver, and the example says so with exit code 1.
    cut = cli(script, "examples", "--run", "hello_fleet.py", "--max-steps", "50")
    assert cut.returncode == 1, cut.stdout + cut.stderr
    assert "0/4 pallets delivered" in cut.stdout


def test_examples_run_a_scenario_with_run_options(script):
    result = cli(script, "examples", "--run", "pick_drop", "--duration", "2", "--rtf", "0")
    assert result.returncode == 0, result.stderr
    summary = summary_of(result.stdout)
    assert (summary["robots"], summary["steps"]) == ("3", "20")


def test_examples_run_unknown_name_suggests(script):
    result = cli(script, "examples", "--run", "hello")
    assert result.returncode == 2
    assert "did you mean 'hello_fleet'?" in error_line(result.stderr)


def test_examples_copy_then_refuse_to_overwrite(script, tmp_path):
    target = tmp_path / "mine"
    first = cli(script, "examples", "--copy", target)
    assert first.returncode == 0, first.stderr
    copied = (target / "hello_fleet.py").read_text()
    assert copied == (REPO / "examples" / "hello_fleet.py").read_text()
    assert (target / "scenarios" / "pick_drop.yaml").is_file()
    assert not list(target.rglob("__pycache__"))
    (target / "hello_fleet.py").write_text("# my edits\n")
    second = cli(script, "examples", "--copy", target)
    assert second.returncode == 2
    line = error_line(second.stderr)
    assert "not overwriting" in line
    assert str(target / "hello_fleet.py") in line
    assert (target / "hello_fleet.py").read_text() == "# my edits\n"


def test_examples_missing_say_where_they_looked(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(fleet_async, "__file__", str(tmp_path / "fleet_async" / "__init__.py"))
    assert main(["examples"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fleet-async: error: no examples found")
    assert str(tmp_path / "fleet_async" / "examples") in err
    assert str(tmp_path / "examples") in err


def test_examples_of_an_installed_package_come_from_inside_it(tmp_path, monkeypatch, capsys):
    package = tmp_path / "site" / "fleet_async"
    shutil.copytree(REPO / "examples", package / "examples")
    monkeypatch.setattr(fleet_async, "__file__", str(package / "__init__.py"))
    assert main(["examples"]) == 0
    assert f"(from {package / 'examples'})" in capsys.readouterr().out


# ----- bench ----------------------------------------------------------------------------------


def test_bench_json_matches_the_benchmark_script(script):
    result = cli(script, "bench", "--n", "100", "--json")
    assert result.returncode == 0, result.stderr
    (line,) = result.stdout.splitlines()
    report = json.loads(line)
    assert report["n"] == 100
    assert report["step_ms"] > 0
    wrapper = subprocess.run(
        [sys.executable, str(REPO / "benchmarks" / "fleet_bench.py"), "--n", "100", "--json"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert wrapper.returncode == 0, wrapper.stderr
    same = json.loads(wrapper.stdout)
    # The same deterministic workload: identical keys and outcome, only timings differ.
    assert same.keys() == report.keys()
    assert (same["moving_after"], same["collisions"]) == (
        report["moving_after"],
        report["collisions"],
    )


def test_bench_rejects_a_non_positive_size(capsys):
    assert main(["bench", "--n", "0"]) == 2
    assert "fleet-async: error: --n: fleet sizes must be > 0, got 0" in capsys.readouterr().err


def test_progress_bar_is_erased_before_other_output_and_comes_back():
    now = [0.0]
    stream = FakeTerminal()
    bar = ProgressBar(600.0, stream, min_interval=0.1, clock=lambda: now[0], open_ended=True)
    bar.start()
    out = bar.guard(stream)
    now[0] = 0.5
    assert bar.update(5.0)
    out.write("[t= 5.0 s] picker0 picked tote0\n")
    now[0] = 1.0
    bar.finish(10.0)
    line = "running until done: 5.0 s (at most 600 s)  RTF 10.0x"
    assert stream.getvalue() == (
        f"\r{line}\r{' ' * len(line)}\r[t= 5.0 s] picker0 picked tote0\n"
        "\rrunning until done: 10.0 s (at most 600 s)  RTF 10.0x\n"
    )


def test_native_output_is_hidden_and_python_output_is_not(tmp_path):
    code = (
        "import os, sys\n"
        "from fleet_async.cli.native_output import native_output_hidden\n"
        "with native_output_hidden() as hidden:\n"
        "    os.write(1, b'from C on 1\\n'); os.write(2, b'from C on 2\\n')\n"
        "    print('from Python'); print('to stderr', file=sys.stderr)\n"
        "print(repr(hidden.text), hidden.line_count)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout == "from Python\n'from C on 1\\nfrom C on 2\\n' 2\n"
    assert result.stderr == "to stderr\n"


def test_the_summary_and_the_monitor_count_objects_alike(scenario, monkeypatch, capsys):
    from fleet_async.core.view.monitor import SimulationMonitor

    seen = []
    monkeypatch.setattr(SimulationMonitor, "update", lambda self, *figures: seen.append(figures))
    monkeypatch.setattr("fleet_async.core.view.monitor.DataMonitor.start", lambda self: None)
    sim = load_scenario(scenario, gui_on=False, rtf=None)
    try:
        sim.params.monitor = True
        sim.setup_monitor()
        sim.update_monitor()
    finally:
        sim.close()
    _, _, objects, agents, _ = seen[0]
    assert main(["run", str(scenario), "--duration", "0.1"]) == 0
    summary = summary_of(capsys.readouterr().out)
    assert (summary["objects"], summary["robots"]) == (str(objects), str(agents)) == ("3", "2")


# ----- traces and the viewer ------------------------------------------------------------------


def test_run_trace_writes_a_trace_the_viewer_reads(script, scenario, tmp_path):
    out = tmp_path / "runs" / "tiny.fatrace"
    result = cli(script, "run", scenario, "--duration", "2", "--trace", out, "--trace-every", "2")
    assert result.returncode == 0, result.stderr
    assert summary_of(result.stdout)["trace"] == str(out)
    reader = TraceReader(out)
    assert [f.step for f in reader.frames()] == list(range(0, 21, 2))
    assert sorted(b["name"] for b in reader.bodies.values()) == ["box", "r0", "r1"]


def test_view_shows_a_cut_trace_with_a_warning_and_rejects_a_bad_one(script, scenario, tmp_path):
    out = tmp_path / "t.fatrace"
    assert cli(script, "run", scenario, "--duration", "1", "--trace", out).returncode == 0
    cut = tmp_path / "cut.fatrace"
    cut.write_bytes(out.read_bytes()[:-20])
    viewer = subprocess.Popen(
        [script, "view", str(cut), "--no-browser", "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        warning = viewer.stderr.readline()  # type: ignore[union-attr]
        assert warning.startswith(f"fleet-async: warning: {cut}: truncated: record")
        assert "the viewer shows the readable prefix" in warning
        assert "fleet_async viewer:" in viewer.stdout.readline()  # type: ignore[union-attr]
    finally:
        viewer.send_signal(signal.SIGINT)
        viewer.wait(timeout=30)
    bad = bytearray(out.read_bytes())
    bad[24:28] = b"\xff\xff\xff\xff"  # the META record's payload is no longer JSON
    cut.write_bytes(bytes(bad))
    result = cli(script, "view", cut, "--no-browser")
    assert result.returncode == 2
    line = error_line(result.stderr)
    assert str(cut) in line and "record 0 (META) at byte 16" in line and "versions 1 and 2" in line
    result = cli(script, "view", tmp_path / "missing.fatrace", "--no-browser")
    assert result.returncode == 2 and "no such trace file" in error_line(result.stderr)


def test_view_serves_the_page_and_the_trace(script, scenario, tmp_path):
    out = tmp_path / "t.fatrace"
    assert cli(script, "run", scenario, "--duration", "1", "--trace", out).returncode == 0
    base = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    with subprocess.Popen(
        [script, "view", str(out), "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env=base,
    ) as proc:
        try:
            assert proc.stdout is not None
            line = proc.stdout.readline()  # printed once the server listens
            url = line.split(" at ", 1)[1].split()[0]
            with urllib.request.urlopen(url + "trace", timeout=30) as response:
                assert response.read() == out.read_bytes()
        finally:
            proc.send_signal(signal.SIGINT)
            assert proc.wait(timeout=30) == 0


def test_per_robot_rows_show_shared_names_with_their_ids():
    from fleet_async.cli.run import _shared_names_with_ids

    rows = [{"robot": "twin", "object_id": 3}, {"robot": "twin", "object_id": 4}]
    rows.append({"robot": "solo", "object_id": 5})
    assert [r["robot"] for r in _shared_names_with_ids(rows)] == ["twin#3", "twin#4", "solo"]


def test_recording_progress_lines_where_stderr_is_not_a_terminal(scenario, tmp_path, capsys):
    from fleet_async.cli.run import _report_recording

    sim = load_scenario(scenario, gui_on=False, rtf=0.0)
    try:
        recorder = sim.start_recording(tmp_path / "r.gif", width=64, height=48, renderer="topdown")
        _report_recording(sim, recorder, every=0.0)
        for _ in range(3):
            sim.step_once()
        sim.stop_recording()
    finally:
        sim.close()
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == f"recording {tmp_path / 'r.gif'}: 2 frames, 0.1 s of sim time"
    assert len(lines) == 3
