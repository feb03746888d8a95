from __future__ import annotations

import pytest

from fleet_async.core.view.runner import RealTimePacer


class FakeClock:
    """A wall clock the test moves by hand; sleeping advances it."""

    def __init__(self):
        self.now = 100.0
        self.slept = []

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.slept.append(round(seconds, 9))
        self.now += seconds


def test_pacer_sleeps_when_ahead_of_target_rtf():
    clock = FakeClock()
    pacer = RealTimePacer(2.0, max_steps_per_frame=10, clock=clock, sleep=clock.sleep)
    pacer.start(sim_time=0.0)
    # 1 s of sim time at 2x real time is due at 0.5 s wall; no wall time has passed.
    assert pacer.steps_now(sim_time=1.0, timestep=0.1) == 1
    assert clock.slept == [0.5]


def test_pacer_catches_up_in_bounded_batches():
    clock = FakeClock()
    pacer = RealTimePacer(1.0, max_steps_per_frame=10, clock=clock, sleep=clock.sleep)
    pacer.start(sim_time=0.0)
    clock.now += 0.35  # 0.35 s behind at dt = 0.1: 4 steps are due
    assert pacer.steps_now(sim_time=0.0, timestep=0.1) == 4
    clock.now += 60.0  # far behind: capped at max_steps_per_frame
    assert pacer.steps_now(sim_time=0.0, timestep=0.1) == 10
    assert clock.slept == []


def test_pacer_rejects_non_positive_rtf():
    with pytest.raises(ValueError, match="target_rtf"):
        RealTimePacer(0.0, 10)


def test_run_simulation_with_pacing_still_runs_exact_steps(sim):
    # target_rtf is huge so the test does not wait on the wall clock; the step count is exact.
    sim.params.target_rtf = 1e9
    sim.run_simulation(duration=1.0)
    assert sim.step_count == 10
