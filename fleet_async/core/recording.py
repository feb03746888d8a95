"""Recording the simulation to GIF / MP4 (skeleton: being written)."""

from __future__ import annotations

__all__ = ["RecordingApi"]


class RecordingApi:
    """``start_recording`` / ``stop_recording`` for MultiRobotSimulationCore."""

    def _stop_recording_after_run(self) -> None:
        """Called when ``run_simulation`` ends: save a recording still in progress."""
