"""The simulation's registries: callbacks, plugins, managers and motion systems.

Mixed into the simulation kernel (``kernel.py``), which steps what is registered here.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol, cast

from fleet_async.core.base.scheduling import PeriodicSchedule
from fleet_async.core.sim.plugins import SimPlugin, as_plugin

if TYPE_CHECKING:
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["MotionSystem", "RegistryApi"]


class MotionSystem(Protocol):
    """Something that advances many objects per step (e.g. a vectorised controller)."""

    def advance(self, dt: float) -> None:
        """Move every object this system owns by one step of ``dt`` seconds."""


class RegistryApi:
    """What the simulation calls each step besides its own phases (mixed into the kernel)."""

    # Provided by the simulation kernel.
    _callbacks: PeriodicSchedule
    _plugin_schedule: PeriodicSchedule
    _plugins: list[SimPlugin]
    _managers: list[Any]
    _motion_systems: list[MotionSystem]

    def register_callback(
        self,
        callback: Callable[[MultiRobotSimulationCore, float], Any],
        frequency: float | None = None,
    ) -> None:
        """Call ``callback(sim, dt)`` every step (None) or at ``frequency`` Hz of sim time."""
        self._callbacks.add(callback, frequency, owner="register_callback")

    def unregister_callback(self, callback_func: Callable[..., Any]) -> bool:
        """Remove a callback; return whether it was registered."""
        return self._callbacks.remove(callback_func)

    def register_plugin(
        self,
        plugin_or_cls: SimPlugin | type[SimPlugin],
        config: dict[str, Any] | None = None,
        frequency: float | None = None,
    ) -> SimPlugin:
        """Register a plugin instance, or instantiate a SimPlugin subclass with ``config``.

        Raises:
            TypeError: if the argument is not a SimPlugin or SimPlugin subclass.
            ValueError: if ``config`` is given with an instance.
        """
        plugin = as_plugin(plugin_or_cls, cast("MultiRobotSimulationCore", self), config)
        freq = frequency if frequency is not None else plugin.frequency
        self._plugin_schedule.add(
            plugin.on_step, freq, owner=f"register_plugin({type(plugin).__name__})"
        )
        self._plugins.append(plugin)
        plugin.on_init()
        return plugin

    def register_manager(self, manager: Any) -> None:
        """Keep ``manager`` in sync with removals and resets; duplicate calls are ignored."""
        if any(m is manager for m in self._managers):
            return
        manager.sim_core = self
        self._managers.append(manager)

    def unregister_manager(self, manager: Any) -> bool:
        """Forget a manager; return whether it was registered."""
        for i, m in enumerate(self._managers):
            if m is manager:
                del self._managers[i]
                return True
        return False

    def get_manager(self, name: str) -> Any | None:
        """The registered manager called ``name``, or None."""
        return next((m for m in self._managers if getattr(m, "name", None) == name), None)

    def add_motion_system(self, system: MotionSystem) -> None:
        """Advance ``system`` in every step's motion phase (vectorised controllers)."""
        if system not in self._motion_systems:
            self._motion_systems.append(system)

    def remove_motion_system(self, system: MotionSystem) -> None:
        """Stop advancing ``system``."""
        if system in self._motion_systems:
            self._motion_systems.remove(system)
