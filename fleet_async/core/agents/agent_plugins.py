"""Per-agent plugins: behaviour attached to one agent and stepped with it (e.g. a battery)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from fleet_async.core.base.attr_state import AttributeState
from fleet_async.core.base.config_utils import resolve_class

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent

__all__ = ["AGENT_PLUGIN_REGISTRY", "AgentPlugin", "BatteryPlugin", "create_agent_plugin"]


class AgentPlugin(AttributeState):
    """Base class of per-agent plugins.

    Args:
        agent: The agent this plugin belongs to (``agent.add_plugin`` checks it).
        config: Plugin settings.
    """

    def __init__(self, agent: Agent, config: dict[str, Any] | None = None) -> None:
        self.agent = agent
        self.config: dict[str, Any] = dict(config or {})

    def on_step(self, dt: float) -> None:
        """Called every step after motion, with the step length in seconds."""

    def on_remove(self) -> None:
        """Called when the plugin is removed or its agent leaves the simulation."""


class BatteryPlugin(AgentPlugin):
    """State of charge that drains with distance and time and refills while charging.

    Config keys (all optional):
        initial_soc: Starting state of charge in [0, 1] (default 1.0).
        drain_per_meter: SoC lost per metre travelled (default 0.001).
        drain_per_second: SoC lost per second, moving or not (default 0.0001).
        charge_rate: SoC gained per second while charging (default 0.01).

    Raises:
        ValueError: for an unknown key or a value out of range, naming it.
    """

    DEFAULTS: ClassVar[dict[str, float]] = {
        "initial_soc": 1.0,
        "drain_per_meter": 0.001,
        "drain_per_second": 0.0001,
        "charge_rate": 0.01,
    }

    def __init__(self, agent: Agent, config: dict[str, Any] | None = None) -> None:
        super().__init__(agent, config)
        unknown = sorted(set(self.config) - set(self.DEFAULTS))
        if unknown:
            raise ValueError(
                f"BatteryPlugin: unknown config key(s) {unknown}; valid: {sorted(self.DEFAULTS)}"
            )
        values = {**self.DEFAULTS, **self.config}
        for key, value in values.items():
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not math.isfinite(value)
                or value < 0
            ):
                raise ValueError(
                    f"BatteryPlugin.{key}: expected a finite number >= 0, got {value!r}"
                )
        if values["initial_soc"] > 1.0:
            raise ValueError(
                "BatteryPlugin.initial_soc: expected a value in [0, 1], "
                f"got {values['initial_soc']!r}"
            )
        self.soc = float(values["initial_soc"])
        self.drain_per_meter = float(values["drain_per_meter"])
        self.drain_per_second = float(values["drain_per_second"])
        self.charge_rate = float(values["charge_rate"])
        self.charging = False
        self.distance = 0.0
        self.used = 0.0
        """SoC drawn by driving and by time so far (charging not subtracted; a flat battery
        draws nothing)."""

    def on_step(self, dt: float) -> None:
        """Drain by the distance moved this step and by time; charge when charging."""
        moved = float(np.linalg.norm(self.agent.velocity)) * dt
        self.distance += moved
        drain = self.drain_per_meter * moved + self.drain_per_second * dt
        gain = self.charge_rate * dt if self.charging else 0.0
        self.used += min(drain, self.soc + gain)
        self.soc = min(1.0, max(0.0, self.soc + (gain - drain)))


AGENT_PLUGIN_REGISTRY: dict[str, type[AgentPlugin]] = {"battery": BatteryPlugin}


def create_agent_plugin(agent: Agent, entry: dict[str, Any], where: str = "plugins") -> AgentPlugin:
    """Build a plugin from ``{"type": name | "class": dotted.path, "config": {...}}``.

    Raises:
        ValueError: for a malformed entry or an unknown type, naming it.
    """
    unknown = sorted(set(entry) - {"type", "class", "config"})
    if unknown:
        raise ValueError(
            f"{where}: unknown key(s) {unknown}; expected 'type' or 'class', and 'config'"
        )
    if ("type" in entry) == ("class" in entry):
        raise ValueError(f"{where}: give exactly one of 'type' or 'class', got {entry!r}")
    if "class" in entry:
        cls = resolve_class(str(entry["class"]))
        if not (isinstance(cls, type) and issubclass(cls, AgentPlugin)):
            raise ValueError(f"{where}.class: {entry['class']!r} is not an AgentPlugin subclass")
    else:
        name = entry["type"]
        if name not in AGENT_PLUGIN_REGISTRY:
            raise ValueError(
                f"{where}.type: unknown plugin {name!r}; known: {sorted(AGENT_PLUGIN_REGISTRY)}"
            )
        cls = AGENT_PLUGIN_REGISTRY[name]
    return cls(agent, entry.get("config") or {})
