"""run_sweep: a scenario x a parameter grid x seeds -> one table of fleet KPIs.

The table has one row per run: ``run`` (the run number, see :mod:`fleet_async.sweep.grid`),
one column per swept key, ``seed``, the :class:`~fleet_async.FleetKpis` columns,
``error`` (empty unless the run failed, and then its KPI columns are empty) and ``wall_time_s``
last: the only column that differs between machines and engines.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fleet_async.core import FleetKpis, RobotKpis
from fleet_async.sweep.engines import Engine, PoolEngine
from fleet_async.sweep.grid import SweepPlan
from fleet_async.sweep.lock import TableLock
from fleet_async.sweep.overrides import SweepKeyError
from fleet_async.sweep.scenarios import RunResult, RunSpec, Scenario
from fleet_async.sweep.table import ResultTable

__all__ = ["SweepProgress", "SweepSummary", "result_columns", "robot_columns", "run_sweep"]

RESERVED = ("run", "seed", "error", "wall_time_s", *FleetKpis.columns())
"""Columns of the table that a swept key may not be called."""


@dataclasses.dataclass(frozen=True)
class SweepProgress:
    """Where a sweep stands, after each run.

    Attributes:
        done: Runs with a row (including those found in the table when it started).
        total: Runs in the sweep.
        failed: Rows with an error, among ``done``.
        skipped: Runs found in the table when it started (not run again).
        result: The run that just finished (None for the first report, before any).
    """

    done: int
    total: int
    failed: int
    skipped: int
    result: RunResult | None


@dataclasses.dataclass(frozen=True)
class SweepSummary:
    """What ``run_sweep`` did.

    Attributes:
        total: Runs in the sweep.
        ran: Runs this call executed.
        skipped: Runs already in the table, not run again.
        failed: Rows with an error in the finished table.
        wall_time_s: Wall seconds the call took.
        rows: The finished table's rows, sorted by run number.
        interrupted: Whether Ctrl+C stopped the sweep (then only finished runs have rows).
    """

    total: int
    ran: int
    skipped: int
    failed: int
    wall_time_s: float
    rows: list[dict[str, Any]]
    interrupted: bool = False


def result_columns(keys: list[str]) -> list[str]:
    """The summary table's columns for a sweep of ``keys``."""
    return ["run", *keys, "seed", *FleetKpis.columns(), "error", "wall_time_s"]


def robot_columns(keys: list[str]) -> list[str]:
    """The per-robot table's columns for a sweep of ``keys``."""
    return ["run", *keys, "seed", *RobotKpis.columns()]


def _check_keys(scenario: Scenario, keys: list[str]) -> None:
    for key in keys:
        if key in RESERVED:
            raise SweepKeyError(
                f"--set {key}: the table already has a column {key!r}; give the parameter "
                "another name"
            )
    scenario.check_keys(keys)


def _is_failed(row: dict[str, Any]) -> bool:
    return row.get("error") not in (None, "")


def run_sweep(
    scenario: Scenario,
    plan: SweepPlan,
    out: str | Path,
    *,
    engine: Engine | None = None,
    duration: float | None = None,
    robots_out: str | Path | None = None,
    checkpoint: str | Path | None = None,
    unsafe: bool = False,
    on_progress: Callable[[SweepProgress], None] | None = None,
) -> SweepSummary:
    """Run every (grid point, seed) of ``plan`` on ``scenario``; write the table to ``out``.

    Runs that ``out`` already has a row for are skipped (resumption); the finished table is
    sorted by run number, so it does not depend on the engine or on the order runs finished in.

    Args:
        scenario: What to run (:class:`YamlScenario`, :class:`FunctionScenario`).
        plan: The grid and the seeds.
        out: The summary table (``.parquet`` for Parquet, else CSV).
        engine: Where runs execute (default: a :class:`PoolEngine`, one worker per core).
        duration: Sim seconds per run (default: the scenario's).
        robots_out: Also write the per-robot table here.
        checkpoint: Branch every run from this checkpoint (``sim.save_state``): each run
            builds the scenario, restores it, reseeds it with its seed (``sim.reseed``: the
            simulation's generator and every stream of ``sim.rng_for``) and runs ``duration``
            more sim seconds. Workers read the file: on a cluster, it must be at the same path
            on every node.
        unsafe: Also read a format-1 checkpoint (a pickle: reading it runs any code it names).
        on_progress: Called with a :class:`SweepProgress` once at the start and after each run.

    Returns:
        A :class:`SweepSummary`. Ctrl+C stops the sweep (the runs in progress finish on the
        pool) and the summary says ``interrupted``; running it again continues.

    Raises:
        SweepKeyError: for a key the scenario does not have (naming the valid ones).
        ValueError: if ``out`` holds a table of another sweep.
        SweepLockedError: while another sweep writes ``out`` (an OS lock on ``<out>.lock``,
            dropped by the kernel when its holder exits, even by ``kill -9``).
        ImportError: for Parquet without pyarrow, or the Ray engine without Ray.
    """
    t0 = time.perf_counter()
    keys = plan.keys
    _check_keys(scenario, keys)
    locks = [TableLock(path) for path in (out, robots_out) if path is not None]
    try:
        for lock in locks:
            lock.acquire()
        tables = _open_tables(plan, out, robots_out)
        start = None if checkpoint is None else str(Path(checkpoint).resolve())
        return _sweep(scenario, plan, tables, engine, duration, start, unsafe, on_progress, t0)
    finally:
        for lock in locks:
            lock.release()


def _open_tables(
    plan: SweepPlan, out: str | Path, robots_out: str | Path | None
) -> tuple[ResultTable, ResultTable | None]:
    keys = plan.keys
    expected = {index: {"run": index, **point, "seed": seed} for index, point, seed in plan.runs()}
    key_columns = ["run", *keys, "seed"]
    table = ResultTable(out, result_columns(keys), key_columns, expected)
    robots_table = (
        ResultTable(robots_out, robot_columns(keys), key_columns, expected, only_runs=table.runs)
        if robots_out is not None
        else None
    )
    return table, robots_table


def _sweep(
    scenario: Scenario,
    plan: SweepPlan,
    tables: tuple[ResultTable, ResultTable | None],
    engine: Engine | None,
    duration: float | None,
    start: str | None,
    unsafe: bool,
    on_progress: Callable[[SweepProgress], None] | None,
    t0: float,
) -> SweepSummary:
    table, robots_table = tables
    runs = plan.runs()
    done = table.runs
    todo = [
        RunSpec(index, point, seed, scenario, duration, robots_table is not None, start, unsafe)
        for index, point, seed in runs
        if index not in done
    ]
    skipped = len(runs) - len(todo)
    failed = sum(_is_failed(row) for row in table.rows)
    report = on_progress or (lambda progress: None)
    report(SweepProgress(skipped, len(runs), failed, skipped, None))
    interrupted = False
    engine = engine if engine is not None else PoolEngine()
    try:
        for n, result in enumerate(engine.map_unordered(todo), start=1):
            keys_row = {"run": result.index, **result.params, "seed": result.seed}
            if robots_table is not None and result.robots:
                robots_table.append({**keys_row, **robot} for robot in result.robots)
            table.append(
                [
                    {
                        **keys_row,
                        **(result.kpis or {}),
                        "error": result.error,
                        "wall_time_s": result.wall_time_s,
                    }
                ]
            )
            failed += result.error is not None
            report(SweepProgress(skipped + n, len(runs), failed, skipped, result))
    except KeyboardInterrupt:
        interrupted = True
    finally:
        table.finish()
        if robots_table is not None:
            robots_table.finish()
    return SweepSummary(
        total=len(runs),
        ran=len(table.rows) - skipped,
        skipped=skipped,
        failed=failed,
        wall_time_s=time.perf_counter() - t0,
        rows=table.rows,
        interrupted=interrupted,
    )
