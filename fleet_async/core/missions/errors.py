"""The errors of the mission seam: raised by the core's awaitables and by the mission layer."""

from __future__ import annotations

__all__ = ["ExternallyDrivenError", "MissionError", "NoMissionRuntimeError"]


class MissionError(Exception):
    """Base class of mission-layer errors."""


class NoMissionRuntimeError(MissionError, RuntimeError):
    """A sim-time await was used outside a mission started by ``fleet_async.run`` (no run in
    progress, another thread, or a plain task of the host loop)."""


class ExternallyDrivenError(MissionError, RuntimeError):
    """A mission commanded an agent that another process drives (a served fleet's master)."""
