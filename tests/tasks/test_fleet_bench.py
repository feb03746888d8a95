"""The mission-overhead benchmark compares like with like: missions and action queues doing the
same work end in the same state (``benchmarks/mission_fleet_bench.py``; not timed here)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "mission_fleet_bench.py"
WARMUP, N = 10, 4
CARRYING, LOOPED = 150, 190
"""Timed steps after which every tote is on its way back (carried), and after which every
robot has finished its second loop (the tote back where it started, the robot on its way home)."""


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    spec = importlib.util.spec_from_file_location("mission_fleet_bench", BENCH)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def queues(bench: ModuleType) -> dict[int, dict[str, Any]]:
    return {steps: bench.run_mode("queues", N, steps, WARMUP)[1] for steps in (CARRYING, LOOPED)}


def test_the_queue_runs_do_the_work(bench: ModuleType, queues: dict[int, dict[str, Any]]) -> None:
    xs = bench.SPACING * np.arange(N)
    carrying, looped = queues[CARRYING], queues[LOOPED]
    assert carrying["step"] == WARMUP + CARRYING
    assert carrying["completed"] == [7] * N  # two loops of four, less the drop under way
    assert carrying["carried"] == [True] * N
    np.testing.assert_allclose(carrying["totes"][:, :2], carrying["robots"][:, :2])
    assert looped["completed"] == [8] * N  # two loops
    assert looped["carried"] == [False] * N
    np.testing.assert_allclose(looped["totes"], np.column_stack([xs, [2.0] * N, [0.1] * N]))
    np.testing.assert_allclose(looped["robots"][:, 0], xs)
    assert np.all((looped["robots"][:, 1] > 0.0) & (looped["robots"][:, 1] < 1.0))  # going home


@pytest.mark.parametrize("steps", [CARRYING, LOOPED])
@pytest.mark.parametrize("mode", ["asyncio", "trio"])
def test_missions_end_where_queues_end(
    bench: ModuleType, queues: dict[int, dict[str, Any]], mode: str, steps: int
) -> None:
    missions = bench.run_mode(mode, N, steps, WARMUP)[1]
    assert bench.same_state(missions, queues[steps]), (missions, queues[steps])


def test_prequeued_queues_end_there_too(
    bench: ModuleType, queues: dict[int, dict[str, Any]]
) -> None:
    prequeued = bench.run_mode("queues", N, LOOPED, WARMUP, prequeued=True)[1]
    assert bench.same_state(prequeued, queues[LOOPED])


def test_another_run_length_is_told_apart(
    bench: ModuleType, queues: dict[int, dict[str, Any]]
) -> None:
    assert not bench.same_state(queues[CARRYING], queues[LOOPED])
    shorter = bench.run_mode("asyncio", N, LOOPED - 1, WARMUP)[1]
    assert not bench.same_state(shorter, queues[LOOPED])
