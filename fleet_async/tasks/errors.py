"""Exceptions raised to missions and by the mission runner."""

from __future__ import annotations

from typing import Any

__all__ = [
    "ActionCancelledError",
    "ActionFailedError",
    "MissionDeadlockError",
    "MissionError",
    "MissionStalledError",
    "NoMissionRuntimeError",
]


class MissionError(Exception):
    """Base class of mission-layer errors."""


class ActionFailedError(MissionError):
    """An awaited action ended FAILED.

    Attributes:
        action: The failed action (``action.error_message`` says why).
    """

    def __init__(self, action: Any) -> None:
        self.action = action
        super().__init__(f"{type(action).__name__} failed: {action.error_message}")


class ActionCancelledError(MissionError):
    """An awaited action was cancelled from outside the waiting mission.

    Attributes:
        action: The cancelled action.
    """

    def __init__(self, action: Any) -> None:
        self.action = action
        super().__init__(f"{type(action).__name__} was cancelled: {action.error_message}")


class MissionDeadlockError(MissionError):
    """Missions are alive but every one waits on something only another mission can give."""


class MissionStalledError(MissionError):
    """A mission held the clock (a wall-clock or I/O wait) longer than the watchdog allows."""


class NoMissionRuntimeError(MissionError, RuntimeError):
    """A sim-time await was used outside a mission started by ``fleet_async.run``."""
