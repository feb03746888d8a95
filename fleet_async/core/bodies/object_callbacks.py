"""Per-object callbacks at a frequency (mixed into SimObject).

``obj.register_callback(cb, frequency)`` calls ``cb(obj, dt)`` every ``1 / frequency`` seconds of
sim time, from the step loop's callback phase. Objects without callbacks cost nothing there.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from fleet_async.core.base.scheduling import PeriodicSchedule

if TYPE_CHECKING:
    from fleet_async.core.bodies.host import BodyHost

__all__ = ["ObjectCallbacks"]


class ObjectCallbacks:
    """Callbacks of one object (mixed into SimObject, which creates ``_callbacks``)."""

    _callbacks: PeriodicSchedule
    sim_core: BodyHost | None

    def register_callback(
        self, callback: Callable[[Any, float], Any], frequency: float = 0.25
    ) -> None:
        """Call ``callback(obj, dt)`` every ``1 / frequency`` seconds of sim time.

        ``frequency`` is in Hz, like every other frequency here (the reference API reads it as
        a period in seconds here; see docs/porting.md).

        Raises:
            ValueError: if ``frequency`` is not a number > 0.
        """
        now = 0.0 if self.sim_core is None else self.sim_core.sim_time
        self._callbacks.add(callback, frequency, owner=f"{self!r}.register_callback", now=now)
        if self.sim_core is not None:
            self.sim_core.world.on_object_callbacks_changed(self)  # type: ignore[arg-type]

    def unregister_callback(self, callback: Callable[..., Any]) -> bool:
        """Remove a callback; return whether it was registered."""
        return self._callbacks.remove(callback)

    def has_callbacks(self) -> bool:
        """Whether any per-object callbacks are registered."""
        return len(self._callbacks) > 0

    def execute_callbacks(self, current_time: float) -> None:
        """Run the callbacks due at ``current_time`` (sim seconds)."""
        for callback, dt in self._callbacks.due(current_time):
            callback(self, dt)

    def reset_callbacks(self) -> None:
        """Restart the callback schedule from sim time 0."""
        self._callbacks.reset()

    def callback_steps_until_due(self, step: int, timestep: float, limit: int) -> int:
        """How many steps from ``step`` on (at most ``limit``) run before a callback is due."""
        return self._callbacks.steps_until_due(step, timestep, limit)
