"""SimPlugin: a unit of simulation-wide behaviour with lifecycle hooks."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from fleet_async.core.base.attr_state import AttributeState

if TYPE_CHECKING:
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["SimPlugin", "as_plugin"]


class SimPlugin(AttributeState):
    """Base class for simulation plugins.

    Register with ``sim.register_plugin(MyPlugin, config={...}, frequency=2.0)``. The simulation
    calls :meth:`on_init` once when the plugin is registered, :meth:`on_step` at the plugin's
    frequency (Hz of sim time; None means every step) during the callbacks phase of
    ``step_once``, and :meth:`on_reset` when the simulation is reset.

    Args:
        sim_core: The simulation the plugin belongs to.
        config: Plugin-specific settings (a copy is kept in ``self.config``).

    Attributes:
        frequency: Default step frequency in Hz, overridable at registration.
    """

    frequency: float | None = None

    def __init__(self, sim_core: SimulationKernel, config: dict[str, Any] | None = None) -> None:
        self.sim_core = sim_core
        self.config: dict[str, Any] = dict(config or {})

    def on_init(self) -> None:
        """Called once, right after registration."""

    def on_step(self, dt: float) -> None:
        """Called when due; ``dt`` is the sim time since the previous call (s)."""

    def on_reset(self) -> None:
        """Called after ``sim.reset()`` has cleared the world."""


def as_plugin(
    plugin_or_cls: SimPlugin | type[SimPlugin],
    sim: SimulationKernel,
    config: dict[str, Any] | None,
) -> SimPlugin:
    """The plugin ``register_plugin`` was given, or one made from a SimPlugin subclass.

    Raises:
        TypeError: if the argument is not a SimPlugin or SimPlugin subclass.
        ValueError: if ``config`` is given with an instance.
    """
    if isinstance(plugin_or_cls, type) and issubclass(plugin_or_cls, SimPlugin):
        return plugin_or_cls(sim, config)
    if isinstance(plugin_or_cls, SimPlugin):
        if config is not None:
            raise ValueError("register_plugin: config applies to a plugin class, not an instance")
        return plugin_or_cls
    raise TypeError(
        f"register_plugin: expected a SimPlugin or SimPlugin subclass, got {plugin_or_cls!r}"
    )
