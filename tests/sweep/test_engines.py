"""The same sweep on the process pool and on a local Ray instance gives the same table."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleet_async.sweep import (
    FunctionScenario,
    InlineEngine,
    PoolEngine,
    RayEngine,
    SweepPlan,
    YamlScenario,
    make_engine,
    read_table,
    run_sweep,
)
from tests.sweep.sweep_scenarios import ref

# Missions with random goals, tasks, a failing grid point: 8 runs of 4 s of sim time.
PLAN = SweepPlan({"robots": [1, 3], "fail_at": [-1, 3]}, seeds=[0, 1])
DURATION = 4.0


def table(path: Path) -> list[dict[str, str]]:
    """Every column but the wall time, which is the only one allowed to differ."""
    return [{k: v for k, v in row.items() if k != "wall_time_s"} for row in read_table(path)]


@pytest.fixture(scope="module")
def inline_table(tmp_path_factory: pytest.TempPathFactory) -> list[dict[str, str]]:
    out = tmp_path_factory.mktemp("inline") / "results.csv"
    run_sweep(
        FunctionScenario(ref("random_fleet")), PLAN, out, engine=InlineEngine(), duration=DURATION
    )
    rows = table(out)
    assert len(rows) == 8 and sum(bool(r["error"]) for r in rows) == 2
    assert all(r["tasks_completed"] not in ("", "0") for r in rows if not r["error"])
    return rows


def test_pool_gives_the_inline_table(inline_table, tmp_path):
    out = tmp_path / "pool.csv"
    summary = run_sweep(
        FunctionScenario(ref("random_fleet")), PLAN, out, engine=PoolEngine(2), duration=DURATION
    )
    assert (summary.ran, summary.failed) == (8, 2)
    assert table(out) == inline_table


def test_local_ray_gives_the_pool_table(inline_table, tmp_path):
    import ray  # in the test extra: its absence is a failure, not a skip

    out = tmp_path / "ray.csv"
    engine = RayEngine(workers=2)
    summary = run_sweep(
        FunctionScenario(ref("random_fleet")), PLAN, out, engine=engine, duration=DURATION
    )
    assert not ray.is_initialized()  # the engine stops the instance it started
    assert (summary.ran, summary.failed) == (8, 2)
    assert table(out) == inline_table


def test_a_yaml_scenario_travels_to_pool_workers_as_data(tmp_path):
    scenario_file = tmp_path / "one.yaml"
    scenario_file.write_text(
        "simulation: {timestep: 0.1, duration: 2.0}\n"
        "entities:\n"
        "  - {name: r0, urdf_path: simple_cube, pose: [0, 0, 0.1],\n"
        "     controller: {type: omni, max_linear_vel: 1.0},\n"
        "     actions: [{type: move, path: [[1.0, 0.0, 0.1]]}]}\n"
    )
    scenario = YamlScenario.from_file(scenario_file)
    scenario_file.unlink()  # the workers never read the file
    plan = SweepPlan({"entities.r0.controller.max_linear_vel": [0.5, 2.0]}, seeds=[0])
    out = tmp_path / "results.csv"
    run_sweep(scenario, plan, out, engine=PoolEngine(2))
    rows = read_table(out)
    # 1 m at 5 m/s^2: at 0.5 m/s the move (2.1 s) outlasts the 2 s run; at 2.0 m/s it takes
    # 0.4 s up to speed, 0.1 s cruising and 0.4 s braking, 9 steps.
    assert [row["moving_time_total_s"] for row in rows] == ["2.0", "0.9"]


def test_engines_by_name():
    assert isinstance(make_engine("pool", workers=3), PoolEngine)
    assert make_engine("pool", workers=3).describe() == "pool of 3 workers"
    assert isinstance(make_engine("inline"), InlineEngine)
    assert make_engine("ray", address="auto").describe() == "ray at auto"
    with pytest.raises(ValueError, match="--address is for the Ray engine"):
        make_engine("pool", address="auto")
    with pytest.raises(ValueError, match="unknown engine 'dask'"):
        make_engine("dask")
