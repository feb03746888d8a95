"""A one-line progress bar for long runs, drawn on a terminal only.

The line is rewritten in place with a carriage return, at most once every ``min_interval`` wall
seconds, so a fast simulation does not spend its time printing. On a stream that is not a
terminal (a pipe, a file, a test's captured output) nothing is written at all.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import TextIO

__all__ = ["ProgressBar", "RunsProgressBar", "format_progress", "format_runs_progress"]


def format_progress(sim_elapsed: float, total: float, rtf: float, width: int = 24) -> str:
    """The progress line, e.g. ``[######......]  12.0/40.0 s  30%  RTF 152.3x``.

    Args:
        sim_elapsed: Sim seconds run so far.
        total: Sim seconds the run will take (> 0).
        rtf: Sim seconds per wall second so far (``inf`` before any wall time passed).
        width: Characters inside the brackets.
    """
    fraction = min(max(sim_elapsed / total, 0.0), 1.0) if total > 0 else 1.0
    filled = int(fraction * width)
    rate = f"{rtf:.1f}x" if math.isfinite(rtf) else "-"
    return (
        f"[{'#' * filled}{'.' * (width - filled)}]  {sim_elapsed:.1f}/{total:.1f} s  "
        f"{fraction * 100:3.0f}%  RTF {rate}"
    )


class ProgressBar:
    """Draws :func:`format_progress` on ``stream`` when it is a terminal.

    Args:
        total: Sim seconds the run will take.
        stream: Where to draw (normally ``sys.stderr``); nothing is drawn unless
            ``stream.isatty()`` is true.
        min_interval: Fewest wall seconds between two redraws; the first draw also waits this
            long, so runs shorter than that show no bar.
        clock: Wall clock in seconds (injectable for tests).
    """

    def __init__(
        self,
        total: float,
        stream: TextIO,
        min_interval: float = 0.1,
        clock: Callable[[], float] = time.perf_counter,
    ) -> None:
        isatty = getattr(stream, "isatty", None)
        self.enabled = bool(isatty is not None and isatty())
        self.total = total
        self._stream = stream
        self._min_interval = min_interval
        self._clock = clock
        self._wall0 = clock()
        self._last_draw = self._wall0
        self._drawn_width = 0

    @property
    def drawn(self) -> bool:
        """Whether the bar has been drawn at least once."""
        return self._drawn_width > 0

    def start(self) -> None:
        """Anchor the real-time factor and the first-draw delay at the current wall time."""
        self._wall0 = self._last_draw = self._clock()

    def update(self, sim_elapsed: float) -> bool:
        """Redraw if enabled and ``min_interval`` has passed since the last draw.

        Args:
            sim_elapsed: Sim seconds run since the start.

        Returns:
            Whether the line was drawn.
        """
        if not self.enabled:
            return False
        now = self._clock()
        if now - self._last_draw < self._min_interval:
            return False
        self._last_draw = now
        self._draw(sim_elapsed, now)
        return True

    def finish(self, sim_elapsed: float) -> None:
        """Draw the final state and end the line, if the bar was drawn at all."""
        if self.drawn:
            self._draw(sim_elapsed, self._clock())
            self._stream.write("\n")
            self._stream.flush()

    def _draw(self, sim_elapsed: float, now: float) -> None:
        wall = now - self._wall0
        rtf = sim_elapsed / wall if wall > 0 else math.inf
        line = format_progress(sim_elapsed, self.total, rtf)
        # Pad over what is left of a longer previous line.
        padding = " " * max(0, self._drawn_width - len(line))
        self._stream.write(f"\r{line}{padding}")
        self._stream.flush()
        self._drawn_width = len(line)


def format_runs_progress(
    done: int, total: int, failed: int, eta: float | None, width: int = 24
) -> str:
    """The progress line of a sweep, e.g. ``[######......]  37/100 runs  2 failed  ETA 41 s``.

    Args:
        done: Runs with a row so far.
        total: Runs in the sweep (> 0).
        failed: Rows with an error among ``done``.
        eta: Wall seconds left (None: not known yet).
        width: Characters inside the brackets.
    """
    fraction = min(max(done / total, 0.0), 1.0) if total > 0 else 1.0
    filled = int(fraction * width)
    left = "ETA -" if eta is None else f"ETA {eta:.0f} s"
    return f"[{'#' * filled}{'.' * (width - filled)}]  {done}/{total} runs  {failed} failed  {left}"


class RunsProgressBar(ProgressBar):
    """Draws :func:`format_runs_progress` on ``stream`` when it is a terminal.

    Args:
        total: Runs in the sweep.
        stream: Where to draw (normally ``sys.stderr``).
        skipped: Runs already done when the sweep started (they do not count towards the ETA).
        min_interval: Fewest wall seconds between two redraws.
        clock: Wall clock in seconds (injectable for tests).
    """

    def __init__(
        self,
        total: int,
        stream: TextIO,
        skipped: int = 0,
        min_interval: float = 0.1,
        clock: Callable[[], float] = time.perf_counter,
    ) -> None:
        super().__init__(float(total), stream, min_interval, clock)
        self.skipped = skipped
        self.failed = 0

    def _draw(self, done: float, now: float) -> None:
        ran = done - self.skipped
        wall = now - self._wall0
        eta = (self.total - done) * wall / ran if ran > 0 and wall > 0 else None
        line = format_runs_progress(int(done), int(self.total), self.failed, eta)
        padding = " " * max(0, self._drawn_width - len(line))
        self._stream.write(f"\r{line}{padding}")
        self._stream.flush()
        self._drawn_width = len(line)
