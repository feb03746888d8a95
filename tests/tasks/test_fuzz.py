"""Differential fuzzing of the mission kernel (hypothesis).

Random mission programs (``programs.py``) run once on asyncio and several times on trio: the
traces must be identical, with no internal error, conservation after every event, every slot
free and every request queue empty at the end. Programs that SimPy can express also run on
SimPy, whose trace must match. A program run in pieces (``run(until=t)`` suspending, the next
run continuing) must give the trace of the uncut run.

The suite runs a fast profile; ``FLEET_ASYNC_FUZZ=N`` runs N examples per test (the long
profile: ``FLEET_ASYNC_FUZZ=10000 python -m pytest tests/tasks/test_fuzz.py``).
"""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fleet_async import MultiRobotSimulationCore, SimulationParams
from tests.tasks.programs import Program, programs, run_fleet, run_simpy

EXAMPLES = int(os.environ.get("FLEET_ASYNC_FUZZ", "60"))
TRIO_RUNS = 3

_settings = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=EXAMPLES <= 60,  # the suite's profile is the same every run
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


@pytest.fixture(scope="module")
def sim():
    params = SimulationParams(
        gui=False, monitor=False, target_rtf=0.0, timestep=1.0, enable_floor=False
    )
    with MultiRobotSimulationCore(params) as sim:
        yield sim


def _same_on_every_backend(sim: MultiRobotSimulationCore, program: Program) -> list:
    reference = run_fleet(sim, program, "asyncio")
    for _ in range(TRIO_RUNS):
        assert run_fleet(sim, program, "trio") == reference
    return reference[0]


@_settings
@given(program=programs(full=True))
def test_every_program_runs_the_same_on_asyncio_and_trio(sim, program):
    _same_on_every_backend(sim, program)


@_settings
@given(program=programs(full=False))
def test_simpy_expressible_programs_match_simpy(sim, program):
    trace = _same_on_every_backend(sim, program)
    assert trace == run_simpy(program)


@_settings
@given(program=programs(full=True), data=st.data())
def test_a_run_cut_into_pieces_gives_the_uncut_runs_trace(sim, program, data):
    cuts = data.draw(st.lists(st.integers(1, program.until - 1), max_size=4), label="cuts")
    uncut = run_fleet(sim, program, "asyncio")
    assert run_fleet(sim, program, "asyncio", tuple(cuts)) == uncut
    assert run_fleet(sim, program, "trio", tuple(cuts)) == uncut
