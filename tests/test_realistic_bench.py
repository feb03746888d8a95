"""The realistic-fleet workload gives the same trace on the vectorized paths and on the
per-robot reference paths (batteries stepped robot by robot, controllers polled every step,
callbacks scanned, attachments recomputed in full), with the numpy code and with the compiled
kernels, at a size where the patrols' goals start in one batch."""

from __future__ import annotations

from fleet_async import realistic_bench
from fleet_async.core.motion.goal_starts import BATCH_MIN


def _same_steps(fast: list, slow: list) -> dict:
    """The vectorized run's frames, each equal to the reference run's frame of its step."""
    assert fast[-1] == slow[-1]  # KPIs (summary and per robot) and the collision count
    fast_steps = {frame[0]: frame for frame in fast[:-1]}
    slow_steps = {frame[0]: frame for frame in slow[:-1]}
    assert set(fast_steps) <= set(slow_steps)
    for step, frame in fast_steps.items():
        assert frame == slow_steps[step], step
    return fast_steps


def test_vectorized_and_reference_paths_give_the_same_trace():
    fast = realistic_bench.trace(60, seconds=25.0, reference=False)
    slow = realistic_bench.trace(60, seconds=25.0, reference=True)
    assert fast[-1] == slow[-1]  # KPIs (summary and per robot) and the collision count
    fast_steps = {frame[0]: frame for frame in fast[:-1]}
    slow_steps = {frame[0]: frame for frame in slow[:-1]}
    # The reference path polls controllers every step, so it never skips; the vectorized
    # path may skip idle spans, and every step it ran must match.
    assert len(slow_steps) == 250 and set(fast_steps) <= set(slow_steps)
    assert len(fast_steps) > 200
    for step, frame in fast_steps.items():
        assert frame == slow_steps[step], step
    summary = fast[-1][0]
    assert summary.distance_total_m > 50.0 and summary.actions_completed > 20
    assert summary.battery_min_soc < 1.0
    assert sum(fast[-2][4]) == 6 * 25  # six robots with a 1 Hz callback, 25 s


def test_batched_goals_and_compiled_kernels_give_the_reference_trace():
    n = 3 * BATCH_MIN + 30  # a third patrol, together: their goals start in one batch
    fast = realistic_bench.trace(n, seconds=12.0, reference=False, kernels="numba")
    slow = realistic_bench.trace(n, seconds=12.0, reference=True)
    steps = _same_steps(fast, slow)
    assert len(steps) > 100
    assert fast[-1][0].actions_completed > 20
