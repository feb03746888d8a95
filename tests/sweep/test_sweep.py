"""run_sweep: the table, failed runs, resumption, the per-robot table, Parquet."""

from __future__ import annotations

import csv
from collections.abc import Iterator, Sequence
from pathlib import Path

import pytest

from fleet_async.core import FleetKpis, RobotKpis
from fleet_async.sweep import (
    FunctionScenario,
    InlineEngine,
    RunResult,
    RunSpec,
    SweepKeyError,
    SweepPlan,
    read_table,
    result_columns,
    run_sweep,
)
from tests.sweep.sweep_scenarios import ref

PLAN = SweepPlan({"robots": [1, 2, 3], "fail_at": [-1, 3]}, seeds=[0, 1])  # 12 runs, 2 fail
DURATION = 4.0


def scenario() -> FunctionScenario:
    return FunctionScenario(ref("random_fleet"))


def without_wall_time(path: Path) -> list[dict[str, str]]:
    return [{k: v for k, v in row.items() if k != "wall_time_s"} for row in read_table(path)]


class StopAfter(InlineEngine):
    """Runs ``n`` specs, then raises KeyboardInterrupt as Ctrl+C would."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.ran: list[int] = []

    def map_unordered(self, specs: Sequence[RunSpec]) -> Iterator[RunResult]:
        for result in super().map_unordered(specs[: self.n]):
            self.ran.append(result.index)
            yield result
        raise KeyboardInterrupt


class Recording(InlineEngine):
    """Runs every spec and remembers which, in reverse order (finish order must not matter)."""

    def __init__(self) -> None:
        self.ran: list[int] = []

    def map_unordered(self, specs: Sequence[RunSpec]) -> Iterator[RunResult]:
        for result in super().map_unordered(list(reversed(specs))):
            self.ran.append(result.index)
            yield result


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The whole sweep, run inline in order, uninterrupted."""
    out = tmp_path_factory.mktemp("reference") / "results.csv"
    summary = run_sweep(scenario(), PLAN, out, engine=InlineEngine(), duration=DURATION)
    assert (summary.total, summary.ran, summary.skipped, summary.failed) == (12, 12, 0, 2)
    return out


def test_the_table_has_a_row_per_run_sorted_with_its_columns(reference):
    with reference.open(newline="") as stream:
        header = next(csv.reader(stream))
    assert header == [
        "run",
        "robots",
        "fail_at",
        "seed",
        *FleetKpis.columns(),
        "error",
        "wall_time_s",
    ]
    rows = read_table(reference)
    assert [row["run"] for row in rows] == [str(i) for i in range(12)]
    assert [(row["robots"], row["fail_at"], row["seed"]) for row in rows[:3]] == [
        ("1", "-1", "0"),
        ("1", "3", "0"),
        ("2", "-1", "0"),
    ]


def test_a_failed_run_is_a_row_with_its_error_and_no_kpis(reference):
    failed = [row for row in read_table(reference) if row["error"]]
    assert [(row["run"], row["robots"], row["fail_at"]) for row in failed] == [
        ("5", "3", "3"),
        ("11", "3", "3"),
    ]
    assert failed[0]["error"] == "ValueError: no fleet of 3 today"
    assert all(failed[0][c] == "" for c in FleetKpis.columns())


def test_finish_order_does_not_change_the_table(reference, tmp_path):
    out = tmp_path / "reversed.csv"
    engine = Recording()
    run_sweep(scenario(), PLAN, out, engine=engine, duration=DURATION)
    assert engine.ran == list(range(11, -1, -1))
    assert without_wall_time(out) == without_wall_time(reference)


def test_an_interrupted_sweep_continues_where_it_stopped(reference, tmp_path):
    out = tmp_path / "results.csv"
    first = run_sweep(scenario(), PLAN, out, engine=StopAfter(5), duration=DURATION)
    assert first.interrupted and first.ran == 5 and len(read_table(out)) == 5
    engine = Recording()
    second = run_sweep(scenario(), PLAN, out, engine=engine, duration=DURATION)
    assert (second.skipped, second.ran, second.interrupted) == (5, 7, False)
    assert sorted(engine.ran) == list(range(5, 12))  # nothing ran twice
    assert without_wall_time(out) == without_wall_time(reference)


def test_a_row_cut_short_by_a_crash_is_run_again(reference, tmp_path):
    out = tmp_path / "results.csv"
    run_sweep(scenario(), PLAN, out, engine=StopAfter(3), duration=DURATION)
    with out.open("a") as stream:
        stream.write("3,2,-1,1,2,40,4.0,1")  # a row the crash cut off: no end of line
    engine = Recording()
    run_sweep(scenario(), PLAN, out, engine=engine, duration=DURATION)
    assert sorted(engine.ran) == list(range(3, 12))
    assert without_wall_time(out) == without_wall_time(reference)


def test_more_seeds_extend_a_finished_table(reference, tmp_path):
    out = tmp_path / "results.csv"
    out.write_text(reference.read_text())
    engine = Recording()
    longer = SweepPlan(PLAN.grid, seeds=[0, 1, 2])
    summary = run_sweep(scenario(), longer, out, engine=engine, duration=DURATION)
    assert (summary.skipped, summary.ran) == (12, 6) and sorted(engine.ran) == list(range(12, 18))
    assert without_wall_time(out)[:12] == without_wall_time(reference)


def test_a_table_of_another_sweep_is_refused(reference, tmp_path):
    out = tmp_path / "results.csv"
    out.write_text(reference.read_text())
    other_values = SweepPlan({"robots": [1, 4, 3], "fail_at": [-1, 3]}, seeds=[0, 1])
    with pytest.raises(ValueError, match=r"run 2 has robots='2' there.*robots='4'"):
        run_sweep(scenario(), other_values, out, engine=InlineEngine(), duration=DURATION)
    other_keys = SweepPlan({"robots": [1, 2]}, seeds=[0])
    with pytest.raises(ValueError, match="holds a table of another sweep"):
        run_sweep(scenario(), other_keys, out, engine=InlineEngine(), duration=DURATION)


def test_unknown_and_reserved_keys_fail_before_anything_runs(tmp_path):
    out = tmp_path / "results.csv"
    with pytest.raises(SweepKeyError, match="takes no parameter 'robot'"):
        run_sweep(scenario(), SweepPlan({"robot": [1]}, seeds=[0]), out, engine=InlineEngine())
    with pytest.raises(SweepKeyError, match="already has a column 'steps'"):
        run_sweep(scenario(), SweepPlan({"steps": [1]}, seeds=[0]), out, engine=InlineEngine())
    assert not out.exists()


def test_the_per_robot_table_resumes_with_the_summary(tmp_path):
    out, robots = tmp_path / "results.csv", tmp_path / "robots.csv"
    plan = SweepPlan({"robots": [1, 2]}, seeds=[0, 1])
    run_sweep(scenario(), plan, out, engine=StopAfter(3), duration=DURATION, robots_out=robots)
    with robots.open("a") as stream:  # a run whose robots were written but not its summary
        stream.write("3,2,1,r0,0,1.0,1.0,0.0,0.0,1,0,0,1,0,0,,\n")
    run_sweep(scenario(), plan, out, engine=InlineEngine(), duration=DURATION, robots_out=robots)
    rows = read_table(robots)
    assert list(rows[0]) == ["run", "robots", "seed", *RobotKpis.columns()]
    assert [(r["run"], r["robot"]) for r in rows] == [
        ("0", "r0"),
        ("1", "r0"),
        ("1", "r1"),
        ("2", "r0"),
        ("3", "r0"),
        ("3", "r1"),
    ]
    assert rows[4]["distance_m"] != "1.0"  # the stale row was dropped and the run redone


def test_parquet_tables_resume_through_their_journal(reference, tmp_path):
    out = tmp_path / "results.parquet"
    run_sweep(scenario(), PLAN, out, engine=StopAfter(4), duration=DURATION)
    journal = tmp_path / "results.parquet.partial.jsonl"
    assert out.exists() and not journal.exists()  # the journal is folded in when it stops
    run_sweep(scenario(), PLAN, out, engine=Recording(), duration=DURATION)
    rows = read_table(out)
    assert [row["run"] for row in rows] == list(range(12))
    assert isinstance(rows[0]["distance_total_m"], float) and rows[5]["distance_total_m"] is None
    as_text = [
        {k: "" if v is None else str(v) for k, v in row.items() if k != "wall_time_s"}
        for row in rows
    ]
    assert as_text == without_wall_time(reference)
    assert list(rows[0]) == result_columns(["robots", "fail_at"])
