"""Exceptions raised to missions and by the mission runner."""

from __future__ import annotations

from typing import Any

from fleet_async.core.missions import ExternallyDrivenError, MissionError, NoMissionRuntimeError

__all__ = [
    "ActionCancelledError",
    "ActionFailedError",
    "Cancelled",
    "ExternallyDrivenError",
    "Interrupt",
    "MissionCancelledError",
    "MissionDeadlockError",
    "MissionError",
    "MissionStalledError",
    "NoMissionRuntimeError",
]


class Cancelled(BaseException):  # named like trio's and anyio's cancellation
    """Thrown into a mission whose cancel scope was cancelled (a sim-time timeout, a task
    group that failed, a lost race, ``mission.cancel()``).

    It is a BaseException, so ``except Exception`` does not swallow it; let it propagate
    (clean up in ``finally``). The scope that was cancelled catches it. Inside missions this is
    the cancellation to expect, on every backend: ``anyio.get_cancelled_exc_class()`` names
    the host event loop's own, which missions never see.
    """


class Interrupt(Exception):  # SimPy's name for it
    """Raised inside a mission by ``mission.interrupt(cause)``; the mission may catch it and
    go on (an awaited action was cancelled, its robot stopped).

    Attributes:
        cause: What the interrupter passed.
    """

    def __init__(self, cause: Any = None) -> None:
        super().__init__(cause)

    @property
    def cause(self) -> Any:
        """The interrupter's cause."""
        return self.args[0]

    def __str__(self) -> str:
        return f"Interrupt({self.cause!r})"


class MissionCancelledError(MissionError):
    """Joining a mission that was cancelled (it has no result)."""


class ActionFailedError(MissionError):
    """An awaited action ended FAILED.

    Attributes:
        action: The failed action (``action.error_message`` says why).
    """

    def __init__(self, action: Any) -> None:
        self.action = action
        super().__init__(f"{type(action).__name__} failed: {action.error_message}")

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (self.action,), self.__dict__


class ActionCancelledError(MissionError):
    """An awaited action was cancelled from outside the waiting mission.

    Attributes:
        action: The cancelled action.
    """

    def __init__(self, action: Any) -> None:
        self.action = action
        super().__init__(f"{type(action).__name__} was cancelled: {action.error_message}")

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (self.action,), self.__dict__


class MissionDeadlockError(MissionError):
    """Missions are alive but every one waits on something only another mission can give."""


class MissionStalledError(MissionError):
    """A mission held the clock (a wall-clock or I/O wait) longer than the watchdog allows."""
