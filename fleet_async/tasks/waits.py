"""Waits that the step loop ends: actions, predicates checked after each step, bus events.

``agent.move(...)`` (and pick, drop, wait, charge, move_joints, reach_pose, submit) queues an
action at once and returns an :class:`ActionWait`: an event that succeeds with the action when
it completes, or fails with ActionFailedError / ActionCancelledError. Actions that end during a
step resume their missions at the step's end, before anything else due then but starts and
interrupts, in agent order (the STEP class). A mission that stops waiting on one because it
was cancelled or interrupted cancels the action (a queued one is dropped, a running one stops
its robot in that step), unless another mission still waits on it.
"""

from __future__ import annotations

import logging
import threading
from typing import TYPE_CHECKING, Any

from fleet_async.core.missions import ActionStatus, MoveAction, WaitAction
from fleet_async.tasks.errors import ActionCancelledError, ActionFailedError
from fleet_async.tasks.kernel import PENDING, SimEvent

if TYPE_CHECKING:
    from collections.abc import Callable, Generator

    from fleet_async.tasks.missions import Mission
    from fleet_async.tasks.runtime import Runtime

logger = logging.getLogger(__name__)

_thread = threading.get_ident

__all__ = ["ActionWait", "BusWait", "PredicateWait", "action_error"]


def action_error(action: Any) -> BaseException | None:
    """What awaiting ``action`` raises once it has ended (None when it completed)."""
    if action.status is ActionStatus.FAILED:
        return ActionFailedError(action)
    if action.status is ActionStatus.CANCELLED:
        return ActionCancelledError(action)
    return None


class ActionWait(SimEvent):
    """A queued action, as an event and a handle: ``await`` it, ``cancel()`` it, watch its
    ``status``, ``phase`` and ``progress``.

    Args:
        runtime: The mission runtime.
        agent: The robot whose queue holds the action.
        action: The action.
        detached: The action outlives the mission that queued it; its failure is logged.
        what: How messages name the call that queued it (``agent.move`` ...).
    """

    __slots__ = ("_runtime", "action", "agent", "detached", "owner", "what")

    fails_run_unhandled = False  # the robot's outcome: on the bus, and raised when awaited

    def __init__(
        self,
        runtime: Runtime,
        agent: Any,
        action: Any,
        detached: bool = False,
        what: str = "agent.submit",
    ) -> None:
        # SimEvent's fields set here rather than through super(): one is made per action.
        kernel = self.kernel = runtime.kernel
        self.callbacks = []
        self.raw_value = PENDING
        self.ok = True
        self._runtime = runtime
        self.agent = agent
        self.action = action
        self.detached = detached
        self.what = what
        owner = kernel.current
        self.owner: Mission | None = None
        """The mission that queued the action and owns it until it ends (None: detached, or
        queued outside a mission)."""
        if not detached and owner is not None:
            self.owner = owner
            owner.own(self)
        if action.is_complete():
            self.settle(in_step=False)
        else:
            runtime.action_waits[id(action)] = self

    def settle(self, in_step: bool) -> None:
        """The action ended: trigger with its outcome (ordered as a step outcome if it ended
        during a step)."""
        owner = self.owner
        if owner is not None:
            self.owner = None
            owner.disown(self)
        error = action_error(self.action)
        if error is None:
            self.ok, self.raw_value = True, self.action
        else:
            self.ok, self.raw_value = False, error
            if self.detached and self.action.status is ActionStatus.FAILED:
                logger.warning("detached %s of %r failed: %s", self.what, self.agent.name, error)
        if in_step:
            self._runtime.outcome(self)
        else:
            self.kernel.schedule(self)

    def abandon(self, mission: Any, cancelled: bool = True) -> None:
        """Its only waiter stopped waiting (cancelled or interrupted): cancel the action
        (whose end then settles this event, so awaiting it again raises
        ActionCancelledError)."""
        if self.callbacks or self.action.is_complete():
            return  # another mission still waits on it, or it is over
        self.action.cancel()

    def drop_owned(self) -> None:
        """The mission that queued the action ended: cancel the action if it is unfinished
        (a queued one is dropped, a running one stops its robot)."""
        if not self.action.is_complete():
            self.action.cancel()

    def __await__(self) -> Generator[Any, Any, Any]:
        kernel = self.kernel
        if kernel.current is None:
            if not self.callbacks:  # nobody else waits: nothing keeps it moving for nobody
                self.action.cancel()
            raise kernel.outside_error(f"{self.what}(...)")
        if _thread() != kernel.thread:  # SimEvent.__await__'s check, inlined
            raise kernel.outside_error("awaiting a sim event")
        return (yield self)

    # ----- the handle -----------------------------------------------------------------------

    @property
    def status(self) -> ActionStatus:
        """The action's status."""
        status: ActionStatus = self.action.status
        return status

    @property
    def done(self) -> bool:
        """Whether the action has ended."""
        return bool(self.action.is_complete())

    @property
    def phase(self) -> Any:
        """The pick / drop phase, or None for actions without phases."""
        return getattr(self.action, "phase", None)

    @property
    def progress(self) -> float:
        """Rough completion in [0, 1]: waypoints reached for moves, time spent for waits."""
        action = self.action
        if action.is_complete():
            return 1.0
        if action.start_time is None:
            return 0.0
        if isinstance(action, WaitAction):
            if action.duration <= 0:
                return 0.0
            now = self._runtime.sim.sim_time
            return float(min(1.0, (now - action.start_time) / action.duration))
        if isinstance(action, MoveAction):
            total = len(action.path)
            return min(1.0, self.agent.current_waypoint_index / total) if total else 0.0
        return 0.0

    def cancel(self) -> None:
        """Cancel the action (a queued one is dropped, a running one stops its robot now)."""
        self.action.cancel()

    def __repr__(self) -> str:
        return f"<ActionWait {type(self.action).__name__} {self.action.status.value}>"


class PredicateWait(SimEvent):
    """``sim.wait_until(predicate)``: succeeds at once if the predicate holds, else after the
    first step at whose end it holds while something waits on it (a predicate nobody awaits,
    such as one that lost an ``any_of``, is not evaluated)."""

    __slots__ = ("_runtime", "predicate")

    def __init__(self, runtime: Runtime, predicate: Callable[[], bool]) -> None:
        super().__init__(runtime.kernel)
        self._runtime = runtime
        self.predicate = predicate
        if predicate():
            self.succeed()
        else:
            runtime.predicates[id(self)] = self

    def abandon(self, mission: Mission, cancelled: bool = True) -> None:
        """Its only waiter stopped waiting: stop checking the predicate."""
        if not self.callbacks:
            self._runtime.predicates.pop(id(self), None)


class BusWait(SimEvent):
    """``sim.events.wait(name, where)``: succeeds with the payload (a dict) of the next
    ``name`` event that ``where(**payload)`` accepts."""

    __slots__ = ("_runtime", "name", "where")

    def __init__(self, runtime: Runtime, name: str, where: Callable[..., bool] | None) -> None:
        super().__init__(runtime.kernel)
        self._runtime = runtime
        self.name = name
        self.where = where
        runtime.add_bus_wait(self)

    def abandon(self, mission: Mission, cancelled: bool = True) -> None:
        """Its only waiter stopped waiting: stop listening."""
        if not self.callbacks:
            self._runtime.bus_waits.get(self.name, {}).pop(id(self), None)
