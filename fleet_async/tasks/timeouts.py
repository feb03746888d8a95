"""Sim-time cancel scopes: ``sim.move_on_after`` / ``sim.fail_after`` and their ``_at`` forms.

Each is an anyio CancelScope with no wall-clock deadline; the runtime cancels it when the
simulation reaches the deadline step, so nesting, ``shield`` and ``cancelled_caught`` behave
exactly as in anyio. The deadline is in whole steps: ``move_on_after(s)`` fires after
``ceil(s / timestep)`` steps.
"""

from __future__ import annotations

from types import TracebackType
from typing import TYPE_CHECKING

import anyio

if TYPE_CHECKING:
    from fleet_async.tasks.runtime import Runtime

__all__ = ["SimTimeout"]


class SimTimeout:
    """A cancel scope that fires at a step; ``fail=True`` raises TimeoutError when it fires.

    Attributes:
        scope: The underlying anyio CancelScope.
        deadline_step: The step count at which the scope is cancelled.
    """

    def __init__(
        self, runtime: Runtime, deadline_step: int, fail: bool, shield: bool = False
    ) -> None:
        self._runtime = runtime
        self.deadline_step = deadline_step
        self._fail = fail
        self.scope = anyio.CancelScope(shield=shield)
        self._entry: tuple[int, int, SimTimeout] | None = None
        self.fired = False

    @property
    def deadline(self) -> float:
        """Sim time (s) at which the scope fires."""
        return self.deadline_step * self._runtime.sim.params.timestep

    @property
    def cancelled_caught(self) -> bool:
        """Whether the scope absorbed the cancellation it caused."""
        return self.scope.cancelled_caught

    @property
    def cancel_called(self) -> bool:
        """Whether the scope has been cancelled (by the deadline or by ``cancel``)."""
        return self.scope.cancel_called

    def cancel(self) -> None:
        """Cancel now, as anyio's ``CancelScope.cancel``."""
        self.scope.cancel()

    def fire(self) -> None:
        """Called by the runtime at the deadline."""
        self.fired = True
        self._entry = None
        self.scope.cancel()

    def __enter__(self) -> SimTimeout:
        self._runtime.current("sim.move_on_after / sim.fail_after")
        if self.deadline_step <= self._runtime.sim.step_count:
            self.fired = True
            self.scope.cancel()
        else:
            self._entry = self._runtime.add_timeout(self, self.deadline_step)
        self.scope.__enter__()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> bool:
        if self._entry is not None:
            self._runtime.remove_timeout(self._entry)
            self._entry = None
        swallowed = bool(self.scope.__exit__(exc_type, exc, tb))
        if self._fail and self.fired and self.scope.cancelled_caught:
            raise TimeoutError(f"sim-time deadline {self.deadline:.3f} s passed")
        return swallowed
