"""Per-agent plugins: behaviour attached to one agent and stepped with it (e.g. a battery)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

from fleet_async.core.agents.batteries import FIELDS, BatteryBank
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

    Every battery of a simulation lives in the fleet's battery bank (``agents/batteries.py``):
    driving steps are applied to all of them in one numpy pass, and a robot standing still
    costs nothing per step, so batteries do not stop idle steps from being skipped. The
    state of charge of a standing robot follows one formula whether its steps ran or were
    skipped.

    Config keys (all optional):
        initial_soc: Starting state of charge in [0, 1] (default 1.0).
        drain_per_meter: SoC lost per metre travelled (default 0.001).
        drain_per_second: SoC lost per second, moving or not, charging or not
            (default 0.0001).
        charge_rate: SoC gained per second while charging (default 0.01).
        discharge_rate: SoC lost per second while moving and not charging (default 0.0;
            pybullet-fleet's key of that name, with its meaning).
        idle_rate: SoC lost per second while standing and not charging (default 0.0;
            pybullet-fleet's key of that name, with its meaning).

    Raises:
        ValueError: for an unknown key or a value out of range, naming it.
    """

    DEFAULTS: ClassVar[dict[str, float]] = {
        "initial_soc": 1.0,
        "drain_per_meter": 0.001,
        "drain_per_second": 0.0001,
        "charge_rate": 0.01,
        "discharge_rate": 0.0,
        "idle_rate": 0.0,
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
            _check_rate(key, value)
        if values["initial_soc"] > 1.0:
            raise ValueError(
                "BatteryPlugin.initial_soc: expected a value in [0, 1], "
                f"got {values['initial_soc']!r}"
            )
        fields = {name: float(values.get(name, 0.0)) for name in FIELDS}
        fields["soc0"] = float(values["initial_soc"])
        self._bank = BatteryBank(_never, 1.0, capacity=1)  # its own, until a fleet adopts it
        self._slot = self._bank.add(fields, 0, False, -1, False)

    # ----- where the state lives (called by FleetMotion) ----------------------------------

    def move_to(self, bank: BatteryBank, row: int, vector: bool) -> None:
        """Move this battery's state into ``bank`` (a fleet's; ``row``: its agent's row;
        ``vector``: stepped by the bank's numpy pass). Not for users."""
        old, slot = self._bank, self._slot
        now = old.now()
        old.reanchor(slot, now)
        values = old.snapshot(slot)
        charging = bool(old.charging[slot])
        old.release(slot)
        step0 = bank.now() if bank is not old else now
        self._bank, self._slot = bank, bank.add(values, step0, charging, row, vector)

    def leave_bank(self) -> None:
        """Take this battery's state out of its fleet's bank (its agent left). Not for
        users."""
        self.move_to(BatteryBank(_never, 1.0, capacity=1), -1, False)

    @property
    def bank(self) -> BatteryBank:
        """The bank that holds this battery's state."""
        return self._bank

    @property
    def bank_slot(self) -> int:
        """This battery's slot in :attr:`bank`."""
        return self._slot

    @property
    def steps_per_agent(self) -> bool:
        """Whether the fleet must call :meth:`on_step` for this battery every step (a
        subclass that overrides it, or the per-robot reference path)."""
        return type(self).on_step is not BatteryPlugin.on_step

    # ----- state -----------------------------------------------------------------------------

    @property
    def soc(self) -> float:
        """State of charge in [0, 1], now."""
        return self._bank.standing(self._slot, self._bank.now())[0]

    @soc.setter
    def soc(self, value: float) -> None:
        _check_rate("soc", value)
        bank, slot = self._bank, self._slot
        bank.reanchor(slot, bank.now())
        bank.values["soc0"][slot] = min(1.0, float(value))

    @property
    def used(self) -> float:
        """SoC drawn by driving and by time so far (charging not subtracted; a flat battery
        draws nothing)."""
        return self._bank.standing(self._slot, self._bank.now())[1]

    @property
    def distance(self) -> float:
        """Metres driven so far."""
        return float(self._bank.values["distance"][self._slot])

    @property
    def charging(self) -> bool:
        """Whether the battery is charging."""
        return bool(self._bank.charging[self._slot])

    @charging.setter
    def charging(self, value: bool) -> None:
        bank, slot = self._bank, self._slot
        if bool(bank.charging[slot]) != bool(value):
            bank.reanchor(slot, bank.now())
            bank.charging[slot] = bool(value)

    drain_per_meter = property(
        lambda self: self._rate("drain_per_meter"),
        lambda self, v: self._set_rate("drain_per_meter", v),
        doc="SoC lost per metre travelled.",
    )
    drain_per_second = property(
        lambda self: self._rate("drain_per_second"),
        lambda self, v: self._set_rate("drain_per_second", v),
        doc="SoC lost per second, moving or not, charging or not.",
    )
    charge_rate = property(
        lambda self: self._rate("charge_rate"),
        lambda self, v: self._set_rate("charge_rate", v),
        doc="SoC gained per second while charging.",
    )
    discharge_rate = property(
        lambda self: self._rate("discharge_rate"),
        lambda self, v: self._set_rate("discharge_rate", v),
        doc="SoC lost per second while moving and not charging.",
    )
    idle_rate = property(
        lambda self: self._rate("idle_rate"),
        lambda self, v: self._set_rate("idle_rate", v),
        doc="SoC lost per second while standing and not charging.",
    )

    def _rate(self, name: str) -> float:
        return float(self._bank.values[name][self._slot])

    def _set_rate(self, name: str, value: float) -> None:
        _check_rate(name, value)
        bank, slot = self._bank, self._slot
        bank.reanchor(slot, bank.now())
        bank.values[name][slot] = float(value)

    def charging_steps_to(self, level: float, dt: float, limit: int) -> int | None:
        """The fewest whole steps of ``dt`` seconds of charging, standing still from now,
        after which the state of charge is at least ``level``, by the same formula the
        bank evaluates (0 if it is there already; None if it never gets there within
        ``limit`` steps)."""
        soc = self.soc
        if soc >= level:
            return 0
        gain, drain = self.charge_rate, self.drain_per_second  # charging: no idle_rate
        if not gain - drain > 0:
            return None

        def after(k: int) -> float:
            return min(1.0, max(0.0, soc + (gain - drain) * (k * dt)))

        k = max(1, math.ceil((level - soc) / ((gain - drain) * dt)) - 2)
        while k > 1 and after(k - 1) >= level:
            k -= 1
        while after(k) < level:
            k += 1
            if k > limit:
                return None
        return k

    # ----- stepping and checkpoints --------------------------------------------------------------

    def on_step(self, dt: float) -> None:
        """Apply the step that is ending to the battery, one robot at a time (the bank's
        numpy pass does the same for batteries whose class keeps this method): the
        per-robot reference. Called by the fleet after the step's motion."""
        bank = self._bank
        bank.drive_one(self._slot, bank.now() - 1)

    def get_state(self) -> dict[str, Any]:
        """The battery's state (``sim.save_state``): ``soc``, ``used``, ``distance`` and
        ``charging`` as they are now, and the anchor the bank evaluates from, which is what
        :meth:`set_state` takes back (so a restored run continues to the bit)."""
        bank, slot = self._bank, self._slot
        state = {k: v for k, v in vars(self).items() if k not in ("_bank", "_slot")}
        state.update(soc=self.soc, used=self.used, distance=self.distance, charging=self.charging)
        state["battery"] = bank.snapshot(slot)
        state["battery_step0"] = int(bank.step0[slot])
        return state

    def set_state(self, state: dict[str, Any]) -> None:
        """Take back what :meth:`get_state` returned (``sim.restore_state``)."""
        state = dict(state)
        values = state.pop("battery")
        step0 = state.pop("battery_step0")
        charging = state.pop("charging")
        for derived in ("soc", "used", "distance"):
            state.pop(derived, None)
        vars(self).update(state)
        bank, slot = self._bank, self._slot
        for name, value in values.items():
            bank.values[name][slot] = value
        bank.step0[slot] = step0
        bank.charging[slot] = bool(charging)


def _never() -> int:
    """The clock of a battery outside any simulation: time does not pass for it."""
    return 0


def _check_rate(key: str, value: Any) -> None:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or value < 0
    ):
        raise ValueError(f"BatteryPlugin.{key}: expected a finite number >= 0, got {value!r}")


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
