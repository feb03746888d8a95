"""Step timing and memory figures, wrapped around the step loop rather than inside it."""

from __future__ import annotations

import logging
import time
import tracemalloc
from collections import defaultdict
from collections.abc import Callable, Sequence

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

    def run(self, phases: Sequence[Phase]) -> dict[str, float]:
        """Run ``phases`` in order; return ``{phase: ms, ..., custom: ms, "total": ms}``."""
        clock = time.perf_counter
        timings: dict[str, float] = {}
        start = clock()
        for name, phase in phases:
            t0 = clock()
            phase()
            timings[name] = (clock() - t0) * 1000.0
        timings["total"] = (clock() - start) * 1000.0
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

    def _accumulate(self, timings: dict[str, float]) -> None:
        for key, value in timings.items():
            self._totals[key] += value
        self._steps += 1
        if self.log_summary and self._steps % self.interval == 0:
            summary = ", ".join(f"{k}={v:.3f}" for k, v in self.means().items())
            logger.info("step profile over %d steps (ms/step): %s", self._steps, summary)


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
