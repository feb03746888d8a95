"""Scenario sweeps: a scenario x a parameter grid x seeds -> one table of fleet KPIs.

A single simulation is one process; what grows past a machine is the number of scenarios.
``run_sweep`` runs every (grid point, seed) of a :class:`SweepPlan` on a scenario (a YAML
mapping, or a Python function of a seed and parameters), on a local process pool by default or
on Ray, and writes one row of :class:`~fleet_async.FleetKpis` per run. Runs are
deterministic, so the table is identical whichever engine ran it and in whatever order runs
finished (all but ``wall_time_s``); a failed run is a row with its error; a sweep that is
stopped and started again skips the runs it already has.

Example::

    from fleet_async.sweep import SweepPlan, YamlScenario, run_sweep

    plan = SweepPlan({"entities.pickers.grid.count": [2, 4, 8]}, seeds=range(10))
    run_sweep(YamlScenario.from_file("warehouse.yaml"), plan, "results.csv", duration=300)

The command line: ``fleet-async sweep SCENARIO --seeds 0:100 --set KEY=V1,V2 --out FILE``.
"""

from fleet_async.sweep.engines import (
    ENGINES,
    Engine,
    InlineEngine,
    PoolEngine,
    RayEngine,
    make_engine,
)
from fleet_async.sweep.grid import SweepPlan, parse_assignment, parse_seeds, parse_value
from fleet_async.sweep.lock import SweepLockedError
from fleet_async.sweep.overrides import SweepKeyError, apply_overrides, settable_keys
from fleet_async.sweep.runner import (
    SweepProgress,
    SweepSummary,
    result_columns,
    robot_columns,
    run_sweep,
)
from fleet_async.sweep.scenarios import (
    FunctionScenario,
    RunResult,
    RunSpec,
    Scenario,
    YamlScenario,
    execute_run,
    load_function,
)
from fleet_async.sweep.table import read_table

__all__ = [
    "ENGINES",
    "Engine",
    "FunctionScenario",
    "InlineEngine",
    "PoolEngine",
    "RayEngine",
    "RunResult",
    "RunSpec",
    "Scenario",
    "SweepKeyError",
    "SweepLockedError",
    "SweepPlan",
    "SweepProgress",
    "SweepSummary",
    "YamlScenario",
    "apply_overrides",
    "execute_run",
    "load_function",
    "make_engine",
    "parse_assignment",
    "parse_seeds",
    "parse_value",
    "read_table",
    "result_columns",
    "robot_columns",
    "run_sweep",
    "settable_keys",
]
