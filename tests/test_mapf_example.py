"""The MAPF-map example: its router, and a small run on the test data's MovingAI map and
scenario (the whole example runs in test_examples.py, at 40 robots)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "traffic"


def _example():
    spec = importlib.util.spec_from_file_location(
        "mapf_warehouse", ROOT / "examples" / "mapf_warehouse.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_routes_have_at_most_three_straight_legs_on_free_cells():
    mapf = _example()
    free = np.ones((5, 7), dtype=bool)
    free[2, 0:6] = False  # a wall with a gap at x = 6
    tasks = np.array([[0, 0, 0, 4], [0, 0, 6, 0], [3, 1, 3, 1], [0, 0, 0, 2]])
    found = mapf.routes(free, tasks)
    assert found[0] == [(0, 0), (6, 0), (6, 4), (0, 4)]  # around the wall's end
    assert found[1] == [(0, 0), (6, 0)]
    assert found[2] == [(3, 1)]
    assert found[3] is None  # the goal is in the wall


def test_a_small_run_on_the_scenario_file_prints_its_summary(capsys):
    mapf = _example()
    code = mapf.main(
        [
            "--map", str(DATA / "warehouse-small.map"),
            "--scen", str(DATA / "warehouse-small.scen"),
            "--cell", "1.0",
            "--robots", "3",
            "--duration", "60",
        ]
    )  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0
    assert "map: warehouse-small.map, 33 x 17 cells" in out
    assert "robots: 3 (0 tasks left out" in out
    assert "sim time: 60.0 s in 600 steps" in out
    assert "arrived: 3 of 3 robots at their goals" in out
    assert "collisions: 0 (contacts that began)" in out
