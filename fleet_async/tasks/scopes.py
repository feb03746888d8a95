"""Sim-time cancel scopes, with anyio's shape: ``cancel()``, ``shield``, ``cancel_called``,
``cancelled_caught``, nesting, and a deadline in sim time.

Cancellation is level-triggered, as in trio and anyio: inside a cancelled scope, every sim await
raises :class:`~fleet_async.tasks.errors.Cancelled` (at once, without parking) until the scope is
left, unless a shielded scope inside it protects the await. A mission already parked inside a
scope when it is cancelled gets the cancellation as an URGENT event at the current step (in
the order the scopes were entered), and its awaited action is cancelled. The scope that was
cancelled catches the Cancelled when it propagates out of it (an outer cancelled scope that is
visible through no shield takes it instead).

Every mission has a root scope (``mission.cancel()``) whose parent is its task group's scope,
so cancelling a group's scope reaches every mission in the group and everything they started.
"""

from __future__ import annotations

import math
from types import TracebackType
from typing import TYPE_CHECKING, Any

from fleet_async.core.missions import steps_for
from fleet_async.tasks.errors import Cancelled, Interrupt
from fleet_async.tasks.kernel import PENDING, URGENT, Kernel, SimEvent, Timeout

if TYPE_CHECKING:
    from fleet_async.tasks.missions import Mission

__all__ = ["CancelScope", "Delivery"]


class CancelScope:
    """A cancel scope measured in sim time (``sim.move_on_after``, ``sim.fail_after``,
    ``sim.cancel_scope``).

    Args:
        kernel: The run's kernel.
        deadline_step: The step at which the scope cancels itself (None: no deadline).
        shield: Protect what runs inside from cancellation of outer scopes.
        fail: Raise TimeoutError when the deadline cancelled the scope and it caught that.
        owner: The mission whose root scope this is (root scopes are never entered with
            ``with``).
        parent: The enclosing scope of a mission's root scope.
        root: A root scope (a mission's, or the run's): active from the start.
    """

    def __init__(
        self,
        kernel: Kernel,
        deadline_step: int | None = None,
        shield: bool = False,
        fail: bool = False,
        *,
        owner: Mission | None = None,
        parent: CancelScope | None = None,
        root: bool = False,
    ) -> None:
        self.kernel = kernel
        self._deadline_step = deadline_step
        self._shield = shield
        self._fail = fail
        self.owner = owner
        self.parent = parent
        self.children: dict[CancelScope, None] = {}
        self._timer: Timeout | None = None
        self._active = False
        self.cancel_called = False
        """Whether ``cancel()`` was called or the deadline passed."""
        self.cancelled_caught = False
        """Whether the scope caught the cancellation it caused."""
        self.fired = False
        """Whether the deadline cancelled the scope."""
        if root:
            self._activate()

    # ----- anyio's surface -------------------------------------------------------------------

    @property
    def shield(self) -> bool:
        """Whether cancellation of outer scopes stops at this scope."""
        return self._shield

    @shield.setter
    def shield(self, value: bool) -> None:
        was, self._shield = self._shield, bool(value)
        parent = self.parent
        if was and not self._shield and self._active and parent is not None and parent.cancelled():
            self._deliver()

    @property
    def deadline(self) -> float:
        """Sim time (s) at which the scope cancels itself (``math.inf``: none)."""
        if self._deadline_step is None:
            return math.inf
        return self._deadline_step * self.kernel.timestep

    @deadline.setter
    def deadline(self, t: float) -> None:
        if math.isinf(t) and t > 0:
            self._deadline_step = None
        else:
            self._deadline_step = max(0, steps_for(t, self.kernel.timestep))
        if self._active:
            self._arm()

    def cancel(self) -> None:
        """Cancel the scope now: missions parked inside get Cancelled (URGENT, at this step);
        the running one raises it at its next sim await."""
        if self.cancel_called:
            return
        self.cancel_called = True
        if self._active:
            self.kernel.cancelled_open += 1
            self._disarm()
            self._deliver()

    def __enter__(self) -> CancelScope:
        if self._active or self.owner is not None:
            raise RuntimeError("a cancel scope can be entered only once")
        mission = self.kernel.require_current("entering a sim cancel scope")
        self.owner = mission
        self.parent = mission.scope
        mission.scope = self
        self._activate()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> bool:
        owner = self.owner
        if owner is None or owner.scope is not self:
            raise RuntimeError(
                "cancel scopes must be exited in the reverse order they were entered, by the "
                "mission that entered them"
            )
        owner.scope = self.parent  # type: ignore[assignment]  # entered scopes have a parent
        self.detach()
        if isinstance(exc, Cancelled) and self.cancel_called and not self._outer_cancelled():
            self.cancelled_caught = True
            if self._fail and self.fired:
                raise TimeoutError(f"sim-time deadline {self.deadline:.3f} s passed") from None
            return True
        return False

    # ----- the tree ------------------------------------------------------------------------

    def cancelled(self) -> bool:
        """Whether an await in this scope is cancelled: this scope or an outer one was
        cancelled, and no shield stands in between."""
        scope: CancelScope | None = self
        while scope is not None:
            if scope.cancel_called:
                return True
            if scope.shield:
                return False
            scope = scope.parent
        return False

    def detach(self) -> None:
        """Leave the tree (the scope was exited, or its mission ended)."""
        if not self._active:
            return
        self._active = False
        if self.parent is not None:
            self.parent.children.pop(self, None)
        self._disarm()
        if self.cancel_called:
            self.kernel.cancelled_open -= 1

    def _outer_cancelled(self) -> bool:
        return not self._shield and self.parent is not None and self.parent.cancelled()

    def _activate(self) -> None:
        self._active = True
        if self.parent is not None:
            self.parent.children[self] = None
        if self.cancel_called:
            self.kernel.cancelled_open += 1
        else:
            self._arm()

    def _arm(self) -> None:
        self._disarm()
        step = self._deadline_step
        if step is None or self.cancel_called:
            return
        kernel = self.kernel
        if step <= kernel.now:
            self.fired = True
            self.cancel()
            return
        self._timer = Timeout(kernel, step - kernel.now)
        self._timer.callbacks.append(self._fire)  # type: ignore[union-attr]  # fresh event

    def _disarm(self) -> None:
        timer, self._timer = self._timer, None
        if timer is not None and timer.callbacks:
            timer.callbacks.remove(self._fire)
            self.kernel.disarm(timer)

    def _fire(self, _: SimEvent) -> None:
        self._timer = None
        self.fired = True
        self.cancel()

    def _deliver(self) -> None:
        """Schedule a cancellation for every mission parked in this scope's subtree (not behind
        a shield), in the order the scopes were entered."""
        missions: dict[Mission, None] = {}
        stack = [self]
        while stack:
            scope = stack.pop()
            if scope.owner is not None:
                missions[scope.owner] = None
            stack.extend(reversed([c for c in scope.children if not c.shield]))
        kernel = self.kernel
        for mission in missions:
            if mission.target is not None and mission.raw_value is PENDING:
                kernel.schedule(Delivery(kernel, mission, None), URGENT)


class Delivery(SimEvent):
    """An interrupt or a cancellation on its way to a parked mission (an URGENT event)."""

    __slots__ = ("_is_cancel",)

    per_waiter = True  # each delivery is made for its mission

    def __init__(self, kernel: Kernel, mission: Mission, interrupt: Interrupt | None) -> None:
        super().__init__(kernel)
        self.callbacks = [mission]
        self.ok = False
        self.raw_value = interrupt
        self._is_cancel = interrupt is None

    def guard(self, mission: Mission) -> bool:
        """Whether the delivery still applies; if so, take the mission off what it awaits."""
        target: Any = mission.target
        if mission.raw_value is not PENDING or target is None:
            return False
        if self._is_cancel:
            if target.uncancellable or not mission.scope.cancelled():
                return False  # it left the cancelled scope, or shields itself meanwhile
            self.raw_value = self.kernel.cancelled_exc()
        if target.callbacks is not None:
            target.callbacks.remove(mission)
        if target.abandon is not None:
            target.abandon(mission, self._is_cancel)
        return True
