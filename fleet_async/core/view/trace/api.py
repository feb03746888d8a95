"""``sim.start_trace`` / ``sim.stop_trace`` / ``sim.trace_event``: the simulation's trace API.

Mixed into ``MultiRobotSimulationCore``; the writer itself is ``writer.py``.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

from fleet_async.core.view.trace.writer import TraceWriter

if TYPE_CHECKING:
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["TraceApi"]


class TraceApi:
    """``start_trace`` / ``stop_trace`` / ``trace_event`` for MultiRobotSimulationCore."""

    _tracer: TraceWriter | None = None

    @property
    def tracer(self) -> TraceWriter | None:
        """The running trace writer, or None."""
        tracer = self._tracer
        return tracer if tracer is not None and tracer.is_tracing else None

    def start_trace(
        self,
        path: str | os.PathLike[str] = "run.fatrace",
        every_n_steps: int | None = None,
        *,
        fps: float | None = None,
        flush_seconds: float = 1.0,
    ) -> TraceWriter:
        """Start recording a trace of this run (poses per frame plus the event log).

        The first frame is the state now; later frames are taken after steps. The file is
        complete once :meth:`stop_trace` (or ``close``) has written its end record.

        Args:
            path: Output file; parent directories are created.
            every_n_steps: Record a frame every this many steps (default 1).
            fps: Instead of ``every_n_steps``: frames per sim second (rounded to whole steps).
            flush_seconds: Wall seconds between writes of buffered frames (for live viewing).

        Returns:
            The running writer.

        Raises:
            RuntimeError: if a trace is already running.
            ValueError: for bad arguments, or both ``every_n_steps`` and ``fps``.
        """
        running = self.tracer
        if running is not None:
            raise RuntimeError(
                f"start_trace: a trace to {running.path!r} is already running; call stop_trace()"
            )
        if every_n_steps is not None and fps is not None:
            raise ValueError("start_trace: give every_n_steps or fps, not both")
        sim: SimulationKernel = self  # type: ignore[assignment]  # mixed into the sim
        if fps is not None:
            if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not fps > 0:
                raise ValueError(f"start_trace fps: expected a number > 0, got {fps!r}")
            every_n_steps = max(1, round(1.0 / (fps * sim.params.timestep)))
        writer = TraceWriter(
            sim, path, 1 if every_n_steps is None else every_n_steps, flush_seconds=flush_seconds
        )
        writer.start()
        self._tracer = writer
        return writer

    def stop_trace(self) -> str | None:
        """Finish the running trace (final frame, end record) and close its file.

        Returns:
            The file's path, or None if no trace was running.
        """
        tracer, self._tracer = self._tracer, None
        return tracer.stop() if tracer is not None else None

    def trace_event(self, kind: str, object_id: int | None = None, **data: Any) -> None:
        """Log an event in the running trace (a no-op when no trace runs).

        Fleet code calls it for what the simulator cannot see, e.g.
        ``sim.trace_event("order_assigned", object_id=robot.object_id, order=order.id)``.
        (Actions, collisions, removals and mission errors, from ``MISSION_FAILED``, are
        logged by the trace itself.) The viewer lists the event under ``object_id`` and in
        the run's event log.
        """
        tracer = self._tracer
        if tracer is not None and tracer.is_tracing:
            tracer.event(kind, object_id, **data)
