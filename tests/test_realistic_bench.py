"""The realistic-fleet workload gives the same trace on the vectorized paths and on the
per-robot reference paths (batteries stepped robot by robot, controllers polled every step,
callbacks scanned, attachments recomputed in full)."""

from __future__ import annotations

from fleet_async import realistic_bench


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
