"""Sweeps and the files they share: one writer per table, no orphans, one scalar rule,
sim times that read as written."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fleet_async.cli import main
from fleet_async.core import load_yaml_config
from fleet_async.sweep import (
    FunctionScenario,
    InlineEngine,
    RunSpec,
    SweepLockedError,
    SweepPlan,
    execute_run,
    parse_assignment,
    parse_value,
    read_table,
    run_sweep,
)
from fleet_async.sweep.lock import TableLock
from fleet_async.sweep.table import round_sim_times
from tests.sweep.sweep_scenarios import ref

# ----- one writer per table ---------------------------------------------------------------


def test_a_second_sweep_on_the_same_table_is_refused(tmp_path):
    out = tmp_path / "results.csv"
    holder = TableLock(out)
    holder.acquire()  # another sweep, as far as the OS is concerned
    plan = SweepPlan({}, seeds=[0, 1])
    scenario = FunctionScenario(ref("steps_only"))
    with pytest.raises(SweepLockedError, match=rf"{out} is being written by another sweep"):
        run_sweep(scenario, plan, out, engine=InlineEngine(), duration=0.5)
    assert not out.exists()
    holder.release()
    summary = run_sweep(scenario, plan, out, engine=InlineEngine(), duration=0.5)
    assert summary.ran == 2 and not (tmp_path / "results.csv.lock").exists()


def _children(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                found.append(int(entry.name))
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in ("Z", "X")


def _wait_for(condition, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.1)
    return condition()


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")
def test_workers_die_with_a_killed_sweep_and_a_rerun_resumes(tmp_path):
    out = tmp_path / "results.csv"
    args = [sys.executable, "-m", "fleet_async.cli", "sweep", ref("walkers"), "--seeds", "0:12"]
    args += ["--duration", "60", "--engine", "pool", "--workers", "2", "--out", str(out)]
    args += ["--quiet"]
    parent = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        assert _wait_for(lambda: len(read_table(out)) >= 1 if out.exists() else False, 240)
        workers = _children(parent.pid)
        assert workers, "the pool has workers"
        parent.send_signal(signal.SIGKILL)
        parent.wait()
        # Behaviour, not speed: the watch period is 0.5 s; 5 s is the promise.
        assert _wait_for(lambda: not any(_alive(w) for w in workers), 5.0), [
            w for w in workers if _alive(w)
        ]
    finally:
        if parent.poll() is None:
            parent.kill()
    kept = len(read_table(out))
    assert 1 <= kept < 12
    rerun = subprocess.run(args, capture_output=True, text=True, check=False)
    assert rerun.returncode == 0, rerun.stderr
    rows = read_table(out)
    assert [int(r["run"]) for r in rows] == list(range(12))


# ----- one scalar rule ---------------------------------------------------------------------


@pytest.mark.parametrize("text", ["1:30", "no", "0x1F", "On", "010", "1_000", "2024-01-31"])
def test_set_refuses_what_yaml_1_1_reads_otherwise(text):
    with pytest.raises(ValueError, match=rf"--set value '{text}': '{text}' is ambiguous"):
        parse_value(text)


def test_set_values_follow_the_scalar_rule():
    assert [parse_value(t) for t in ("90", "-3", "0.5", "1e-3", ".5", "inf", "true", "null")] == [
        90,
        -3,
        0.5,
        0.001,
        0.5,
        float("inf"),
        True,
        None,
    ]
    assert parse_value('"no"') == "no" and parse_value("'1:30'") == "1:30"
    assert parse_value("walker") == "walker" and parse_value("[0, 0, 0.1]") == [0, 0, 0.1]
    assert parse_assignment("a.b=1,'0x1F'") == ("a.b", [1, "0x1F"])


def test_scenario_files_follow_the_same_rule(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("simulation:\n  timestep: 0.1\nentities:\n  - name: no\n")
    with pytest.raises(ValueError, match=r"s\.yaml, line 4, column 11: invalid YAML: 'no' is"):
        load_yaml_config(path)
    path.write_text("entities:\n  - name: 'no'\n    wait: 1:30\n")
    with pytest.raises(ValueError, match=r"line 3, column 11: .*'1:30' is ambiguous"):
        load_yaml_config(path)
    path.write_text("entities:\n  - {name: 'no', count: 31, yaw: .5, label: hello}\n")
    assert load_yaml_config(path) == {
        "entities": [{"name": "no", "count": 31, "yaw": 0.5, "label": "hello"}]
    }


def test_the_cli_names_a_refused_set_value(tmp_path, capsys):
    scenario = tmp_path / "one.yaml"
    scenario.write_text("simulation: {timestep: 0.1, duration: 1.0}\n")
    with pytest.raises(SystemExit) as exited:
        main(["sweep", str(scenario), "--set", "simulation.duration=1:30", "--quiet"])
    assert exited.value.code == 2
    assert "'1:30' is ambiguous" in capsys.readouterr().err


# ----- sim times that read as written ----------------------------------------------------


def test_sim_time_columns_are_rounded_to_the_timestep(tmp_path):
    assert round_sim_times({"sim_time_s": 234 * 0.1, "distance_total_m": 0.1 + 0.2}, 0.1) == {
        "sim_time_s": 23.4,
        "distance_total_m": 0.1 + 0.2,
    }
    assert round_sim_times({"idle_time_s": 3 * 0.025}, 0.025) == {"idle_time_s": 0.075}
    spec = RunSpec(0, {}, 0, FunctionScenario(ref("steps_only")), 23.4, True)
    result = execute_run(spec)
    assert result.error is None
    assert result.kpis["sim_time_s"] == 23.4 and repr(result.kpis["sim_time_s"]) == "23.4"
    assert all(repr(r["idle_time_s"]).count("0000") == 0 for r in result.robots)
    out = tmp_path / "t.csv"
    run_sweep(
        FunctionScenario(ref("steps_only")),
        SweepPlan({}, [0]),
        out,
        engine=InlineEngine(),
        duration=23.4,
    )
    assert read_table(out)[0]["sim_time_s"] == "23.4"
    assert os.path.exists(out)
