"""Scenarios that name their missions (core/scenario/missions.py) and run_scenario, which runs
them with the scenario's actions until the work is done or the duration is reached."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import fleet_async as fa
from fleet_async import MultiRobotSimulationCore, run_scenario

REPO = Path(__file__).resolve().parent.parent
HEADLESS = "simulation: {gui: false, monitor: false, target_rtf: 0, timestep: 0.1}\n"
ROBOT = """\
entities:
  - name: r0
    urdf_path: simple_cube
    pose: [0.0, 0.0, 0.1]
    controller: {type: omni, max_linear_vel: 1.0}
"""
MISSIONS_PY = """\
async def drive(sim, distance, speed_note="", *, log=None):
    from fleet_async import Pose

    robot = sim.agents[0]
    await robot.move(Pose.from_xyz(distance, 0, 0.1))
    print(f"r0 arrived at t={sim.sim_time:.1f} {speed_note}".strip())
    return sim.sim_time


async def idle(sim):
    await sim.sleep(1.0)
    return "rested"


def not_async(sim):
    return None
"""


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text))
    return path


@pytest.fixture
def scenario_dir(tmp_path: Path) -> Path:
    write(tmp_path, "my_missions.py", MISSIONS_PY)
    return tmp_path


def load(folder: Path, missions: str, extra: str = "") -> MultiRobotSimulationCore:
    path = write(folder, "scenario.yaml", HEADLESS + extra + ROBOT + missions)
    return MultiRobotSimulationCore.from_yaml(path)


# ----- the missions: section ------------------------------------------------------------------


def test_entries_resolve_beside_the_scenario_with_their_arguments(scenario_dir, capsys):
    sim = load(
        scenario_dir,
        "missions:\n"
        "  - function: my_missions:drive\n    args: [2.0, fast]\n    name: go\n"
        "  - my_missions:idle\n",
    )
    with sim:
        (go, rest) = sim.scenario_missions
        assert (go.name, go.args, go.target) == ("go", (2.0, "fast"), "my_missions:drive")
        assert rest.name == "idle"
        outcome = run_scenario(sim)
    assert outcome.stopped == "done"
    # drive(2.0, "fast"): 2 m at 1 m/s (5 m/s^2): 0.2 s ramping up, 2 s in all, ends at 2.2 s
    assert outcome.results == {"go": pytest.approx(2.2), "idle": "rested"}
    assert capsys.readouterr().out == f"r0 arrived at t={outcome.results['go']:.1f} fast\n"


def test_a_py_file_path_is_relative_to_the_scenario_file(tmp_path):
    write(tmp_path, "code/fleet_code.py", MISSIONS_PY)
    sim = load(
        tmp_path / "scenarios",
        "missions:\n  - function: ../code/fleet_code.py:idle\n",
    )
    with sim:
        assert run_scenario(sim).results == {"idle": "rested"}


def test_the_scenario_folder_wins_over_the_python_path(tmp_path, monkeypatch):
    elsewhere = write(tmp_path / "elsewhere", "my_missions.py", "async def idle(sim):\n    pass\n")
    monkeypatch.syspath_prepend(str(elsewhere.parent))
    write(tmp_path / "here", "my_missions.py", MISSIONS_PY)
    with load(tmp_path / "here", "missions: [my_missions:idle]\n") as sim:
        assert run_scenario(sim).results == {"idle": "rested"}


def test_a_module_not_beside_the_scenario_comes_from_the_python_path(tmp_path, monkeypatch):
    write(tmp_path / "lib", "fleet_lib_for_test.py", MISSIONS_PY)
    monkeypatch.syspath_prepend(str(tmp_path / "lib"))
    with load(tmp_path / "scenario", "missions: [fleet_lib_for_test:idle]\n") as sim:
        assert sim.scenario_missions[0].function.__module__ == "fleet_lib_for_test"


@pytest.mark.parametrize(
    ("missions", "fragments"),
    [
        ("missions: {a: 1}\n", ["missions: expected a list"]),
        ("missions: [my_missions]\n", ["missions[0].function", "expected 'module:function'"]),
        ("missions: [nowhere:idle]\n", ["missions[0].function", "cannot find module 'nowhere'"]),
        ("missions: [my_missions:nap]\n", ["has no function 'nap'", "drive, idle"]),
        ("missions: [my_missions:not_async]\n", ["not an async function"]),
        ("missions: [../gone.py:idle]\n", ["no mission file '../gone.py'"]),
        ("missions: [{function: my_missions:idle, arg: [1]}]\n", ["unknown key 'arg'", "args"]),
        ("missions: [{args: [1]}]\n", ["missions[0]: missing 'function"]),
        ("missions: [{function: my_missions:idle, args: 3}]\n", ["missions[0].args"]),
        (
            "missions: [{function: my_missions:drive, kwargs: {speed: 2}}]\n",
            ["missions[0]", "drive(sim, *args, **kwargs)", "kwargs={'speed': 2}"],
        ),
        ("missions: [my_missions:idle, my_missions:idle]\n", ["missions[1].name", "twice"]),
    ],
)
def test_bad_entries_name_the_file_the_entry_and_the_value(scenario_dir, missions, fragments):
    with pytest.raises(ValueError, match=r"scenario\.yaml: missions") as info:
        load(scenario_dir, missions)
    message = str(info.value)
    assert message.startswith(str(scenario_dir / "scenario.yaml"))
    for fragment in fragments:
        assert fragment in message


def test_a_mission_module_that_fails_to_import_is_named(scenario_dir):
    write(scenario_dir, "broken.py", "raise RuntimeError('boom')\n")
    with pytest.raises(ValueError, match=r"missions\[0\]\.function: importing .*broken.py "):
        load(scenario_dir, "missions: [broken:idle]\n")


# ----- how long a run lasts -------------------------------------------------------------------


def test_a_duration_runs_exactly_that_long_and_cancels_what_is_left(scenario_dir):
    with load(scenario_dir, "missions: [{function: my_missions:drive, args: [50]}]\n") as sim:
        outcome = run_scenario(sim, 3.0)
        assert (outcome.stopped, sim.step_count, outcome.results) == ("duration", 30, {})


def test_the_scenario_duration_applies_when_none_is_given(scenario_dir):
    timed = HEADLESS.replace("timestep: 0.1}", "timestep: 0.1, duration: 2.0}")
    path = write(scenario_dir, "timed.yaml", timed + ROBOT + "missions: [my_missions:idle]\n")
    with MultiRobotSimulationCore.from_yaml(path) as sim:
        outcome = run_scenario(sim)
        assert (outcome.stopped, outcome.results) == ("duration", {"idle": "rested"})
        assert sim.step_count == 20


def test_without_work_a_run_stops_at_the_cap(scenario_dir):
    with load(scenario_dir, "") as sim:
        outcome = run_scenario(sim, max_duration=4.0)
        assert (outcome.stopped, sim.step_count) == ("no_end", 40)
        assert "no missions, no actions and no duration" in outcome.describe()


def test_unfinished_work_stops_at_the_cap(scenario_dir):
    with load(scenario_dir, "missions: [{function: my_missions:drive, args: [500]}]\n") as sim:
        outcome = run_scenario(sim, max_duration=5.0)
        assert (outcome.stopped, sim.step_count) == ("max_duration", 50)


def test_queued_actions_count_as_work(tmp_path):
    path = write(
        tmp_path,
        "acts.yaml",
        HEADLESS + ROBOT + "    actions:\n      - {type: wait, duration: 1.5}\n",
    )
    with MultiRobotSimulationCore.from_yaml(path) as sim:
        assert run_scenario(sim).stopped == "done"
        assert sim.step_count == 15


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_the_same_run_on_both_backends(scenario_dir, backend):
    with load(scenario_dir, "missions: [{function: my_missions:drive, args: [3.0]}]\n") as sim:
        outcome = run_scenario(sim, backend=backend)
        assert outcome.results["drive"] == sim.sim_time


def test_run_scenario_is_public():
    assert fa.run_scenario is run_scenario
    assert "run_scenario" in fa.__all__


# ----- the warehouse demo: the script and the scenario run the same shift ---------------------


def test_fleet_async_run_of_the_warehouse_runs_the_scripts_shift():
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}

    def run(*argv: str) -> str:
        result = subprocess.run(
            [sys.executable, *argv], capture_output=True, text=True, cwd=REPO, env=env, timeout=300
        )
        assert result.returncode == 0, result.stdout + result.stderr
        return result.stdout

    script = run("examples/warehouse_missions.py")
    command = run("-m", "fleet_async", "run", "examples/scenarios/warehouse.yaml")
    assert "shift over: 12/12 orders delivered" in script
    assert command.startswith(script)  # the same lines, then the run summary
    assert "missions:          1" in command
