"""One run: building the scenario, running it, its KPI row or its error."""

from __future__ import annotations

import pickle
import sys
from pathlib import Path

import pytest
import yaml

from fleet_async.core import FleetKpis
from fleet_async.sweep import FunctionScenario, RunSpec, SweepKeyError, YamlScenario, execute_run
from fleet_async.sweep.scenarios import describe_error
from tests.sweep.sweep_scenarios import ref

if sys.version_info < (3, 11):
    from exceptiongroup import ExceptionGroup

TINY = """\
simulation: {timestep: 0.1, duration: 3.0, gui: true}
entities:
  - name: r0
    urdf_path: simple_cube
    pose: [0.0, 0.0, 0.1]
    controller: {type: omni, max_linear_vel: 1.0, max_linear_accel: 10.0}
    actions:
      - {type: move, path: [[1.0, 0.0, 0.1]]}
"""


@pytest.fixture
def tiny(tmp_path: Path) -> YamlScenario:
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY)
    return YamlScenario.from_file(path)


def test_a_yaml_run_is_headless_seeded_and_summarised(tiny):
    result = execute_run(RunSpec(3, {"entities.r0.controller.max_linear_vel": 0.5}, 7, tiny))
    assert result.error is None and (result.index, result.seed) == (3, 7)
    assert list(result.kpis) == FleetKpis.columns()
    # 1 m at 0.5 m/s and 10 m/s^2: 2.05 s of exact trapezoid, arriving in step 21, so 21
    # steps moving and 9 idle over the scenario's 3 s.
    assert result.kpis["steps"] == 30 and result.kpis["moving_time_total_s"] == 2.1
    assert result.kpis["actions_completed"] == 1 and result.robots is None
    assert result.wall_time_s > 0


def test_a_run_duration_overrides_the_scenarios(tiny):
    result = execute_run(RunSpec(0, {}, 0, tiny, duration=0.5, per_robot=True))
    assert result.kpis["steps"] == 5
    assert [r["robot"] for r in result.robots] == ["r0"]


MISSIONS = """\
from fleet_async import Pose, SimEvents


async def deliver(sim, trips=2):
    robot = sim.agents[0]
    for trip in range(trips):
        await robot.move(Pose.from_xyz(1.0 - trip % 2, 0.0, 0.1))
        sim.events.emit(SimEvents.TASK_COMPLETED, sim=sim, agent=robot, task=trip)
"""


def test_a_yaml_run_runs_the_scenarios_missions_until_they_are_done(tmp_path):
    (tmp_path / "trips.py").write_text(MISSIONS)
    path = tmp_path / "trips.yaml"
    scenario = TINY.replace(", duration: 3.0", "").split("    actions:")[0]
    path.write_text(scenario + "missions:\n  - {function: trips:deliver, kwargs: {trips: 3}}\n")
    result = execute_run(RunSpec(0, {}, 0, YamlScenario.from_file(path)))
    assert result.error is None, result.error
    # As under fleet-async run: no duration, so the run ends when the mission has returned.
    assert result.kpis["tasks_completed"] == 3 and result.kpis["actions_completed"] == 3
    assert 0 < result.kpis["sim_time_s"] < 10.0
    timed = execute_run(RunSpec(0, {}, 0, YamlScenario.from_file(path), duration=1.5))
    # Cut short mid-move: the move that the end cancels is not counted.
    assert timed.kpis["steps"] == 15 and timed.kpis["tasks_completed"] == 1
    assert (timed.kpis["actions_failed"], timed.kpis["actions_cancelled"]) == (0, 0)


def test_a_bad_value_is_the_runs_error_not_the_sweeps(tiny):
    result = execute_run(RunSpec(0, {"entities.r0.controller.max_linear_vel": "fast"}, 0, tiny))
    assert result.kpis is None
    assert result.error.startswith("ValueError: ") and "max_linear_vel" in result.error


def test_yaml_keys_are_checked_up_front(tiny):
    tiny.check_keys(["entities.r0.pose", "simulation.timestep"])
    with pytest.raises(SweepKeyError, match=r"entities\.r1"):
        tiny.check_keys(["entities.r1.pose"])


def test_a_function_scenario_runs_its_mission_until_the_duration():
    scenario = FunctionScenario(ref("random_fleet"))
    result = execute_run(RunSpec(0, {"robots": 3}, 5, scenario, duration=10.0))
    assert result.error is None
    kpis = result.kpis
    assert kpis["robot_count"] == 3 and kpis["steps"] == 100 and kpis["sim_time_s"] == 10.0
    assert kpis["tasks_completed"] > 0
    # The missions are cancelled at the end, and their moves with them: not counted.
    assert kpis["actions_cancelled"] == 0 and kpis["actions_failed"] == 0
    again = execute_run(RunSpec(0, {"robots": 3}, 5, scenario, duration=10.0))
    assert again.kpis == kpis
    other_seed = execute_run(RunSpec(0, {"robots": 3}, 6, scenario, duration=10.0))
    assert other_seed.kpis != kpis


def test_a_function_scenario_without_mission_is_stepped():
    result = execute_run(RunSpec(0, {"speed": 2.0}, 1, FunctionScenario(ref("steps_only"))))
    assert result.error is None and result.kpis["steps"] == 50
    assert result.kpis["distance_total_m"] == pytest.approx(2.0, abs=1e-12)


def test_function_keys_are_its_parameters():
    scenario = FunctionScenario(ref("random_fleet"))
    assert scenario.settable_keys() == ["robots", "fail_at"]
    with pytest.raises(SweepKeyError, match=r"takes no parameter 'robot'.*robots, fail_at"):
        scenario.check_keys(["robot"])


def test_a_raising_function_or_a_wrong_return_is_the_runs_error():
    failing = execute_run(
        RunSpec(0, {"robots": 2, "fail_at": 2}, 0, FunctionScenario(ref("random_fleet")))
    )
    assert failing.error == "ValueError: no fleet of 2 today" and failing.kpis is None
    wrong = execute_run(RunSpec(0, {}, 0, FunctionScenario(ref("not_a_sim"))))
    assert wrong.error.startswith("TypeError: ") and "MultiRobotSimulationCore" in wrong.error


def test_a_function_reference_pickles_without_the_function():
    scenario = FunctionScenario(ref("random_fleet"))
    scenario.settable_keys()  # loaded here
    copy = pickle.loads(pickle.dumps(scenario))
    assert copy.reference == scenario.reference and copy.function.__name__ == "random_fleet"


def test_bad_function_references_are_explained():
    with pytest.raises(ValueError, match="MODULE:FUNCTION"):
        FunctionScenario("no_colon").function  # noqa: B018
    with pytest.raises(ValueError, match="no file"):
        FunctionScenario("missing.py:f").function  # noqa: B018
    with pytest.raises(ValueError, match="has no function 'nope'"):
        FunctionScenario(ref("nope")).function  # noqa: B018


def test_errors_read_the_same_in_every_process():
    class Thing:
        pass

    error = ValueError(f"bad {Thing()!r}")
    error.__notes__ = ["in mission 'main' at sim time 1.000 s"]  # add_note on Python >= 3.11
    text = describe_error(ExceptionGroup("group", [error, KeyError("k")]))
    assert " at 0x" not in text
    assert text.startswith("ValueError: bad <")
    assert text.endswith("(in mission 'main' at sim time 1.000 s) | KeyError: 'k'")
    assert describe_error(RuntimeError("two\nlines")) == "RuntimeError: two / lines"


def test_yaml_scenario_round_trips_through_pickle(tiny):
    copy = pickle.loads(pickle.dumps(tiny))
    assert copy.config == yaml.safe_load(TINY) and copy.base_dir == tiny.base_dir


def test_runs_branch_from_a_checkpoint(tmp_path):
    from tests.sweep.sweep_scenarios import steps_only

    warm = steps_only(0, speed=1.0)  # drives 1 m; 6 steps in, it is under way
    for _ in range(6):
        warm.step_once()
    warm.save_state(tmp_path / "warm.ckpt")
    warm.close()
    scenario = FunctionScenario(ref("steps_only"))
    checkpoint = str(tmp_path / "warm.ckpt")
    branch = execute_run(RunSpec(0, {}, 0, scenario, duration=1.0, checkpoint=checkpoint))
    fresh = execute_run(RunSpec(0, {}, 0, scenario, duration=1.0))
    assert branch.error is None and branch.kpis["steps"] == 10
    assert branch.kpis["distance_total_m"] < fresh.kpis["distance_total_m"]  # the rest of 1 m
    wrong = execute_run(
        RunSpec(0, {}, 1, FunctionScenario(ref("random_fleet")), 1.0, False, checkpoint)
    )
    assert wrong.error.startswith(
        "CheckpointError: restore_state: this simulation has other objects"
    )


def test_an_empty_scenario_file_is_refused_naming_it(tmp_path):
    path = tmp_path / "empty.yaml"
    path.write_text("")
    with pytest.raises(ValueError, match=r"empty.yaml: the file is empty"):
        YamlScenario.from_file(path)


def test_seeds_branch_different_runs_from_one_checkpoint(tmp_path):
    from tests.sweep.sweep_scenarios import walkers

    warm = walkers(0)
    for _ in range(30):
        warm.step_once()
    warm.save_state(tmp_path / "warm.ckpt")
    warm.close()
    scenario = FunctionScenario(ref("walkers"))
    checkpoint = str(tmp_path / "warm.ckpt")

    def branch(seed: int) -> dict:
        result = execute_run(RunSpec(0, {}, seed, scenario, 5.0, False, checkpoint))
        assert result.error is None
        return result.kpis

    runs = [branch(seed) for seed in (0, 1, 2)]
    distances = [run["distance_total_m"] for run in runs]
    assert len(set(distances)) == 3  # three seeds, three runs
    assert branch(1) == runs[1]  # the same seed, the same run
