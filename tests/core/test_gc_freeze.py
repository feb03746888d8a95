"""A run keeps the objects that existed when it started out of the garbage collector's full
collections (``SimulationParams.gc_freeze``, ``core/base/memory.py``): frozen for the run,
given back at its end (also when it fails), never when turned off, and a process's own freeze
is left alone."""

from __future__ import annotations

import gc

import pytest

import fleet_async as fa
from fleet_async import MultiRobotSimulationCore
from tests.conftest import headless_params


def _frozen_during_run(sim: MultiRobotSimulationCore) -> list[int]:
    seen: list[int] = []
    sim.add_step_observer(lambda step: seen.append(gc.get_freeze_count()))
    sim.run_simulation(1.0)
    return seen


def test_run_simulation_freezes_the_heap_for_the_run_only() -> None:
    assert gc.get_freeze_count() == 0
    with MultiRobotSimulationCore(headless_params()) as sim:
        seen = _frozen_during_run(sim)
    assert seen and min(seen) > 0
    assert gc.get_freeze_count() == 0


def test_gc_freeze_false_leaves_the_collector_alone() -> None:
    with MultiRobotSimulationCore(headless_params(gc_freeze=False)) as sim:
        seen = _frozen_during_run(sim)
    assert seen and set(seen) == {0}


def test_missions_run_with_the_heap_frozen_and_a_failure_gives_it_back() -> None:
    with MultiRobotSimulationCore(headless_params()) as sim:
        seen: list[int] = []

        async def main() -> None:
            await sim.sleep(0.5)
            seen.append(gc.get_freeze_count())
            raise RuntimeError("mission failed")

        with pytest.raises(RuntimeError, match="mission failed"):
            fa.run(sim, main)
        assert seen and seen[0] > 0
        assert gc.get_freeze_count() == 0
        assert sim.sim_time == pytest.approx(0.5)


def test_a_process_that_froze_objects_itself_keeps_its_freeze() -> None:
    gc.freeze()
    try:
        with MultiRobotSimulationCore(headless_params()) as sim:
            seen = _frozen_during_run(sim)
        assert gc.get_freeze_count() > 0  # the process's freeze was not given back
        assert seen and min(seen) > 0
    finally:
        gc.unfreeze()


def test_gc_freeze_must_be_a_flag() -> None:
    with pytest.raises(ValueError, match=r"gc_freeze.*'yes'"):
        headless_params(gc_freeze="yes")
