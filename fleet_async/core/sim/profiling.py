"""Step timing and memory figures, wrapped around the step loop rather than inside it.

A profiled step reports the reference API's keys (its documentation of ``step_once``), mapped
onto fleet_async's phases:

- ``phase1_update``: ``callbacks`` + ``agent_update`` + ``attachments``;
- ``phase2_pose_flush``: pushing the step's poses to PyBullet (0 when the step needed none:
  headless, kinematic, PyBullet is synced lazily);
- ``phase3_aabb_grid_flush``: the AABB refresh of moved objects, part of ``collision_check``
  here (0 when the collision check did not run);
- ``step_simulation``: 0 unless ``physics=True``;
- ``collision_breakdown``: only when the collision check ran: ``get_aabbs``,
  ``spatial_hashing``, ``aabb_filtering``, ``contact_points``, ``total``;
- ``events_collision``: the collision events' handlers;
- ``monitor_update``: always 0 here, since the monitor is updated by ``run_simulation``
  around the step, not inside it;
- ``agent_update``, ``callbacks``, ``collision_check``, ``events_pre_step``,
  ``events_post_step``, ``total``; and fleet_async's own ``attachments`` and ``safety_fields``.

Fields recorded with ``record_profiling`` are added, summed within the step.
"""

from __future__ import annotations

import logging
import time
import tracemalloc
from collections import defaultdict
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["MemoryProfiler", "StepProfiler"]

logger = logging.getLogger(__name__)

Phase = tuple[str, Callable[[], None]]


class StepProfiler:
    """Times each phase of a step in milliseconds and keeps running totals.

    Args:
        interval: Steps between logged summaries when ``log_summary`` is on.
        log_summary: Log mean phase times every ``interval`` profiled steps.
    """

    def __init__(self, interval: int = 100, log_summary: bool = False) -> None:
        self.interval = interval
        self.log_summary = log_summary
        self._custom: dict[str, float] = defaultdict(float)
        self._totals: dict[str, float] = defaultdict(float)
        self._steps = 0

    def run(
        self,
        phases: Sequence[Phase],
        collision: Callable[[], dict[str, float] | None] = lambda: None,
    ) -> dict[str, Any]:
        """Run ``phases`` in order; return the step's timings in ms (see the module doc).

        Args:
            phases: ``(name, callable)`` pairs, the step loop's phases.
            collision: Returns the collision check's own timings if it ran in this step.
        """
        clock = time.perf_counter
        measured: dict[str, float] = {}
        start = clock()
        for name, phase in phases:
            t0 = clock()
            phase()
            measured[name] = (clock() - t0) * 1000.0
        measured["total"] = (clock() - start) * 1000.0
        timings = reference_timings(measured, collision())
        if self._custom:
            timings.update(self._custom)
            self._custom.clear()
        self._accumulate(timings)
        return timings

    def record(self, name: str, value_ms: float) -> None:
        """Add ``value_ms`` to a custom field of the current step (summed within a step)."""
        self._custom[name] += float(value_ms)

    def discard_custom(self) -> None:
        """Drop custom fields recorded during an unprofiled step."""
        self._custom.clear()

    def means(self) -> dict[str, float]:
        """Mean ms per profiled step for each field so far."""
        n = max(self._steps, 1)
        return {k: v / n for k, v in self._totals.items()}

    def reset(self) -> None:
        """Forget all totals."""
        self._totals.clear()
        self._custom.clear()
        self._steps = 0

    def _accumulate(self, timings: dict[str, Any]) -> None:
        for key, value in timings.items():
            if isinstance(value, float):
                self._totals[key] += value
        self._steps += 1
        if self.log_summary and self._steps % self.interval == 0:
            summary = ", ".join(f"{k}={v:.3f}" for k, v in self.means().items())
            logger.info("step profile over %d steps (ms/step): %s", self._steps, summary)


def reference_timings(
    measured: dict[str, float], collision: dict[str, float] | None
) -> dict[str, Any]:
    """The reference API's profiling keys from the measured phases (see the module doc)."""
    update = measured["callbacks"] + measured["agent_update"] + measured["attachments"]
    timings: dict[str, Any] = {
        "phase1_update": update,
        "phase2_pose_flush": measured.get("pose_flush", 0.0),
        "phase3_aabb_grid_flush": 0.0 if collision is None else collision["get_aabbs"],
        "agent_update": measured["agent_update"],
        "attachments": measured["attachments"],
        "safety_fields": measured.get("safety_fields", 0.0),
        "callbacks": measured["callbacks"],
        "step_simulation": measured.get("step_simulation", 0.0),
        "collision_check": measured["collision_check"],
        "events_pre_step": measured["events_pre_step"],
        "events_post_step": measured["events_post_step"],
        "events_collision": 0.0 if collision is None else collision.get("events", 0.0),
        "monitor_update": 0.0,
        "total": measured["total"],
    }
    if collision is not None:
        timings["collision_breakdown"] = {
            key: collision[key]
            for key in ("get_aabbs", "spatial_hashing", "aabb_filtering", "contact_points", "total")
        }
    return timings


class MemoryProfiler:
    """Python heap usage through tracemalloc (not RSS: C allocations are not counted)."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self._started_here = False
        if enabled and not tracemalloc.is_tracing():
            tracemalloc.start()
            self._started_here = True

    def usage(self) -> dict[str, float] | None:
        """``{"current_mb", "peak_mb"}`` or None when disabled."""
        if not self.enabled or not tracemalloc.is_tracing():
            return None
        current, peak = tracemalloc.get_traced_memory()
        return {"current_mb": current / 2**20, "peak_mb": peak / 2**20}

    def stop(self) -> None:
        """Stop tracing if this profiler started it."""
        if self._started_here and tracemalloc.is_tracing():
            tracemalloc.stop()
        self._started_here = False
