from __future__ import annotations

import pytest

from fleet_async.core.base.scheduling import PeriodicSchedule


def _run(schedule, steps, dt):
    fired = []
    for k in range(steps):
        for cb, elapsed in schedule.due(k * dt, dt):
            fired.append((cb.__name__, k, round(elapsed, 12)))
    return fired


def test_periodic_entry_fires_at_period_multiples_without_drift():
    schedule = PeriodicSchedule()

    def hz4(): ...

    schedule.add(hz4, 4.0)
    fired = _run(schedule, 1001, 0.05)
    steps = [k for _, k, _ in fired]
    # 4 Hz with dt = 0.05 s -> every 5 steps, starting one period in, for 1000 steps exactly.
    assert steps == list(range(5, 1001, 5))
    assert {e for _, _, e in fired} == {0.25}


def test_every_step_entry_gets_step_dt():
    schedule = PeriodicSchedule()

    def each(): ...

    schedule.add(each, None)
    assert _run(schedule, 3, 0.1) == [("each", 0, 0.1), ("each", 1, 0.1), ("each", 2, 0.1)]


def test_faster_than_step_runs_once_per_step_with_elapsed_time():
    schedule = PeriodicSchedule()

    def fast(): ...

    schedule.add(fast, 100.0)
    assert [k for _, k, _ in _run(schedule, 4, 0.1)] == [1, 2, 3]


def test_reset_and_remove():
    schedule = PeriodicSchedule()

    def a(): ...

    schedule.add(a, 1.0)
    assert schedule.due(1.0) and not schedule.due(1.5)
    schedule.reset()
    assert not schedule.due(0.5)
    assert schedule.due(1.0)
    assert schedule.remove(a) and not schedule.remove(a)
    assert len(schedule) == 0


@pytest.mark.parametrize("freq", [0, -1, float("nan"), float("inf"), "10", True])
def test_bad_frequency_is_rejected(freq):
    with pytest.raises(ValueError, match="frequency"):
        PeriodicSchedule().add(lambda: None, freq, owner="register_callback")
