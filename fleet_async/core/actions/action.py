"""Robot actions: the base class, MoveAction and WaitAction.

Actions run from an agent's queue (``agent.add_action``), one at a time. The queue is event
driven: after ``execute`` returns False, :meth:`Action.wait_hint` tells the runner what the
action is waiting for, so an action blocked on motion or on a timer costs nothing per step.

Timing: actions start in the step's action tick (before motion), at that step's sim time. An
action that completes because motion ended completes at the end of that step (sim time + dt),
when the robot is at its goal; the next queued action starts in the following step's tick, at
that same instant.

Called directly (``while not a.is_complete(): a.execute(agent, dt)``, the reference API's
protocol), every built-in action keeps its own ``status``, ``start_time`` and ``end_time``
(:class:`TrackedAction`), and a WaitAction outside a queue counts the ``dt`` it is given.
"""

from __future__ import annotations

import logging
import numbers
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from fleet_async.core.base.reprs import short_repr
from fleet_async.core.base.types import ActionStatus, MovementDirection, coerce_enum
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.waypoints import Path

if TYPE_CHECKING:
    from fleet_async.core.actions.host import ActingAgent

__all__ = [
    "DEFAULT_EE_TOLERANCE",
    "DEFAULT_JOINT_TOLERANCE",
    "DEFAULT_MAX_FORCE",
    "DEFAULT_MOVE_SKIP_THRESHOLD",
    "Action",
    "MoveAction",
    "TrackedAction",
    "WaitAction",
    "WaitHint",
]

logger = logging.getLogger(__name__)

DEFAULT_MOVE_SKIP_THRESHOLD: float = 0.05
"""m: a pick/drop sub-move shorter than this is skipped."""
DEFAULT_MAX_FORCE: float = 500.0
"""N: default motor force for joint / end-effector control."""
DEFAULT_JOINT_TOLERANCE: float = 0.01
"""rad or m: default joint convergence tolerance."""
DEFAULT_EE_TOLERANCE: float = 0.02
"""m: default end-effector convergence tolerance."""

# What an action waits for after execute() returned False: ("poll", None) = run again next
# step; ("motion", None) = run again when the agent's motion ends; ("time", t) = at sim time t.
WaitHint = tuple[str, float | None]


@dataclass(eq=False)
class Action(ABC):
    """Base class of all actions.

    A subclass implements ``execute(agent, dt)`` (one timestep; True once complete) and
    ``reset()``. Run from an agent's queue, the queue keeps ``status`` and the times; a
    subclass may also set them itself, as the built-in actions do (:class:`TrackedAction`).

    Attributes:
        status: Execution status.
        start_time: Sim time the action started, or None.
        end_time: Sim time the action ended, or None.
        error_message: Why it failed or was cancelled, or None.
        awaited: Set by the mission API (``agent.submit`` and the commands built on it) on the
            actions a mission awaits. An awaited MoveAction on a fixed-base agent fails with
            the reason, so the mission sees it; a plain queued one is skipped with a warning,
            as the reference API ignores goals on a fixed base.
    """

    status: ActionStatus = field(default=ActionStatus.NOT_STARTED, init=False)
    start_time: float | None = field(default=None, init=False)
    end_time: float | None = field(default=None, init=False)
    error_message: str | None = field(default=None, init=False)
    awaited: bool = field(default=False, init=False, repr=False)
    _cancel_hook: Callable[[Action], None] | None = field(default=None, init=False, repr=False)

    @abstractmethod
    def execute(self, agent: ActingAgent, dt: float) -> bool:
        """Advance the action; return True once it is complete (successfully or not)."""

    @abstractmethod
    def reset(self) -> None:
        """Return to NOT_STARTED so the action can run again."""

    def wait_hint(self) -> WaitHint:
        """What the action waits for after ``execute`` returned False (default: poll)."""
        return ("poll", None)

    def fail(self, reason: str) -> bool:
        """Mark the action FAILED with ``reason``; returns True (complete) for ``execute``."""
        self.status = ActionStatus.FAILED
        self.error_message = reason
        return True

    def cancel(self) -> None:
        """Cancel: a queued action is dropped, a running one stops its robot this step."""
        if self.is_complete():
            return
        self.status = ActionStatus.CANCELLED
        if self.error_message is None:
            self.error_message = "cancelled"
        hook, self._cancel_hook = self._cancel_hook, None
        if hook is not None:
            hook(self)

    def on_cancel(self, agent: ActingAgent) -> None:  # noqa: B027  # optional hook, empty by default
        """Clean up after being cancelled while running (the queue has already stopped motion)."""

    @property
    def in_queue(self) -> bool:
        """Whether the action sits in an agent's queue or is running from it."""
        return self._cancel_hook is not None

    def bind_cancel_hook(self, hook: Callable[[Action], None] | None) -> None:
        """Set by the action queue: called when :meth:`cancel` runs."""
        self._cancel_hook = hook

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the queue's cancel hook, which the queue binds again (checkpoints)."""
        state = dict(self.__dict__)
        state["_cancel_hook"] = None
        return state

    def get_duration(self) -> float | None:
        """Seconds from start to end (or None if it has not both started and ended)."""
        if self.start_time is None or self.end_time is None:
            return None
        return self.end_time - self.start_time

    def is_complete(self) -> bool:
        """Whether the action has ended: completed, failed or cancelled."""
        return self.status in (ActionStatus.COMPLETED, ActionStatus.FAILED, ActionStatus.CANCELLED)

    def _reset_status(self) -> None:
        self.status = ActionStatus.NOT_STARTED
        self.start_time = None
        self.end_time = None
        self.error_message = None


def _clock(agent: ActingAgent) -> float:
    """The sim time an action run directly reads (0.0 for an agent outside a simulation)."""
    sim = agent.sim_core
    return 0.0 if sim is None else sim.sim_time


class TrackedAction(Action):
    """An action that keeps its own status and times, so it can be run without a queue.

    ``execute`` marks the action IN_PROGRESS (with ``start_time``) on its first call, runs
    :meth:`step`, and once that returns True marks it COMPLETED (unless it failed) with
    ``end_time``. From a queue nothing changes: the queue has set the start already and
    stamps the exact end time afterwards.
    """

    def execute(self, agent: ActingAgent, dt: float) -> bool:
        """Run one timestep of ``dt`` seconds; True once the action is complete."""
        if self.status is ActionStatus.NOT_STARTED:
            self.status = ActionStatus.IN_PROGRESS
            self.start_time = _clock(agent)
        if not self.step(agent, dt):
            return False
        if self.status is ActionStatus.IN_PROGRESS:
            self.status = ActionStatus.COMPLETED
        if self.end_time is None:
            self.end_time = _clock(agent)
        return True

    @abstractmethod
    def step(self, agent: ActingAgent, dt: float) -> bool:
        """The action's own work for one timestep; True once it is done (or :meth:`fail`)."""


def _as_path(path: Any) -> Path:
    if isinstance(path, Path):
        return path
    if isinstance(path, Pose):
        return Path([path])
    if isinstance(path, (list, tuple)) and all(isinstance(p, Pose) for p in path):
        return Path(list(path))
    of_numbers = isinstance(path, (list, tuple)) and path and all(map(_is_number, path))
    hint = " (numbers: for a position give Pose.from_xyz(x, y, z))" if of_numbers else ""
    raise ValueError(
        f"MoveAction.path: expected a Path, a Pose or a list of Poses, got {short_repr(path)} "
        f"({type(path).__name__}){hint}"
    )


def _is_number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


@dataclass(eq=False)
class MoveAction(TrackedAction):
    """Follow a path.

    Args:
        path: Waypoints (a Path, a Pose or a list of Poses).
        auto_approach: Drive from the current pose to the first waypoint (else the first
            waypoint is taken as the start and skipped).
        final_orientation_align: Turn to the last waypoint's orientation at the end.
        direction: "forward", "backward" or "auto" (differential robots).
    """

    path: Path = field(default_factory=lambda: Path([]))
    auto_approach: bool = True
    final_orientation_align: bool = True
    direction: MovementDirection | str = MovementDirection.FORWARD
    _started: bool = field(default=False, init=False, repr=False)

    def __post_init__(self) -> None:
        self.path = _as_path(self.path)
        if len(self.path) == 0:
            raise ValueError("MoveAction.path: expected at least one waypoint, got an empty path")
        self.direction = coerce_enum(MovementDirection, self.direction, "MoveAction.direction")

    def step(self, agent: ActingAgent, dt: float) -> bool:
        """Send the path on the first call; complete when motion ends at the goal.

        On a fixed-base agent the move is skipped with a warning (it completes at once), unless
        a mission awaits it (:attr:`awaited`): then it fails with the reason.
        """
        if not self._started:
            self._started = True
            blocker = agent.motion_blocker
            if blocker is not None and agent.use_fixed_base and not self.awaited:
                logger.warning("MoveAction skipped: %s; goals are ignored", blocker)
                return True
            if blocker is not None:
                return self.fail(f"cannot move: {blocker}")
            agent.set_path(
                self.path.waypoints,
                auto_approach=self.auto_approach,
                final_orientation_align=self.final_orientation_align,
                direction=self.direction,
            )
            return not agent.is_moving and self._finish(agent)
        if agent.is_moving:
            return False
        return self._finish(agent)

    def _finish(self, agent: ActingAgent) -> bool:
        if agent.motion_result is False:
            return self.fail("motion stopped before reaching the goal")
        return True

    def wait_hint(self) -> WaitHint:
        """Waits for the end of motion."""
        return ("motion", None)

    def reset(self) -> None:
        """Forget progress."""
        self._reset_status()
        self._started = False


@dataclass(eq=False)
class WaitAction(TrackedAction):
    """Wait ``duration`` sim seconds; ``action_type="charge"`` charges the battery meanwhile.

    From a queue the wait ends at the exact sim time it covers. Called directly, each
    ``execute(agent, dt)`` counts as ``dt`` seconds: a 1.0 s wait completes on the 10th call
    with ``dt = 0.1``.

    Args:
        duration: Seconds (>= 0).
        action_type: "idle" or "charge" (any label is allowed; "charge" sets charging).
    """

    duration: float = 0.0
    action_type: str = "idle"
    _until: float | None = field(default=None, init=False, repr=False)
    _elapsed: float = field(default=0.0, init=False, repr=False)

    def __post_init__(self) -> None:
        d = self.duration
        if (
            isinstance(d, bool)
            or not isinstance(d, (int, float))
            or not d >= 0
            or d == float("inf")
        ):
            raise ValueError(f"WaitAction.duration: expected a finite number >= 0 (s), got {d!r}")
        self.duration = float(d)

    def step(self, agent: ActingAgent, dt: float) -> bool:
        """Start the timer on the first call; complete once it has run out."""
        sim = agent.sim_core
        if self.in_queue and sim is not None:  # the queue's clock: exact sim times
            now = sim.action_time
        else:  # run directly: the caller's dt is the time that passes per call
            self._elapsed += dt
            now = self._elapsed
        if self._until is None:
            self._until = (now if self.in_queue else 0.0) + self.duration
            if self.action_type == "charge":
                agent.set_charging(True)
        if now + 1e-9 < self._until:
            return False
        if self.action_type == "charge":
            agent.set_charging(False)
        return True

    def wait_hint(self) -> WaitHint:
        """Waits until the end time."""
        return ("time", self._until)

    def on_cancel(self, agent: ActingAgent) -> None:
        """Stop charging if this wait was charging."""
        if self._until is not None and self.action_type == "charge":
            agent.set_charging(False)

    def reset(self) -> None:
        """Forget progress."""
        self._reset_status()
        self._until = None
        self._elapsed = 0.0
