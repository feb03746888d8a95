"""A one-line progress bar for long runs, drawn on a terminal only.

The line is rewritten in place with a carriage return, at most once every ``min_interval`` wall
seconds, so a fast simulation does not spend its time printing. On a stream that is not a
terminal (a pipe, a file, a test's captured output) nothing is written at all. Other output
during the run (a mission's ``print``) goes through :meth:`ProgressBar.guard`, which erases the
bar first, so lines never start in the middle of it; the bar comes back at its next update.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any, TextIO

__all__ = ["ProgressBar", "format_progress"]


def format_progress(
    sim_elapsed: float, total: float, rtf: float, width: int = 24, open_ended: bool = False
) -> str:
    """The progress line, e.g. ``[######......]  12.0/40.0 s  30%  RTF 152.3x``.

    Args:
        sim_elapsed: Sim seconds run so far.
        total: Sim seconds the run will take (> 0); with ``open_ended``, the most it may take.
        rtf: Sim seconds per wall second so far (``inf`` before any wall time passed).
        width: Characters inside the brackets.
        open_ended: The run ends when its work is done, at most at ``total``: no bar, e.g.
            ``running until done: 12.0 s (at most 600 s)  RTF 152.3x``.
    """
    rate = f"{rtf:.1f}x" if math.isfinite(rtf) else "-"
    if open_ended:
        return f"running until done: {sim_elapsed:.1f} s (at most {total:g} s)  RTF {rate}"
    fraction = min(max(sim_elapsed / total, 0.0), 1.0) if total > 0 else 1.0
    filled = int(fraction * width)
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
        open_ended: The run ends when its work is done (``total`` is only its cap).
    """

    def __init__(
        self,
        total: float,
        stream: TextIO,
        min_interval: float = 0.1,
        clock: Callable[[], float] = time.perf_counter,
        open_ended: bool = False,
    ) -> None:
        isatty = getattr(stream, "isatty", None)
        self.enabled = bool(isatty is not None and isatty())
        self.total = total
        self.open_ended = open_ended
        self._stream = stream
        self._min_interval = min_interval
        self._clock = clock
        self._wall0 = clock()
        self._last_draw = self._wall0
        self._drawn_width = 0  # characters of the bar on the terminal's current line
        self._ever_drawn = False

    @property
    def drawn(self) -> bool:
        """Whether the bar has been drawn at least once."""
        return self._ever_drawn

    def clear(self) -> None:
        """Erase the bar from the current line, if it is there (before other output)."""
        if self._drawn_width:
            self._stream.write("\r" + " " * self._drawn_width + "\r")
            self._stream.flush()
            self._drawn_width = 0

    def guard(self, stream: TextIO) -> TextIO:
        """``stream``, wrapped so that every write first erases the bar."""
        return _BarAwareStream(stream, self)  # type: ignore[return-value]  # a TextIO proxy

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
        line = format_progress(sim_elapsed, self.total, rtf, open_ended=self.open_ended)
        # Pad over what is left of a longer previous line.
        padding = " " * max(0, self._drawn_width - len(line))
        self._stream.write(f"\r{line}{padding}")
        self._stream.flush()
        self._drawn_width = len(line)
        self._ever_drawn = True


class _BarAwareStream:
    """A text stream proxy that erases the progress bar before each write."""

    def __init__(self, stream: TextIO, bar: ProgressBar) -> None:
        self._stream = stream
        self._bar = bar

    def write(self, text: str) -> int:
        if text:
            self._bar.clear()
        return self._stream.write(text)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)
