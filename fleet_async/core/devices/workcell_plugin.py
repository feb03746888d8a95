"""WorkcellPlugin: declare dispenser and ingestor stations in a scenario's ``plugins`` section.

YAML::

    plugins:
      - type: workcell
        config:
          processing_time: 2.0          # defaults for every station (any WorkcellParams key)
          item_shape: {shape_type: box, half_extents: [0.1, 0.1, 0.1], rgba_color: [1, 0.6, 0, 1]}
          workcells:
            dispenser_1: {kind: dispenser, position: [0.0, 1.5]}
            ingestor_1:  {kind: ingestor, position: [12.0, 0.0, 3.0], processing_time: 1.0}

Each entry of ``workcells`` becomes a :class:`~fleet_async.core.devices.workcell.Workcell`
named after its key, at ``position`` ([x, y] or [x, y, z]; or ``pose`` / ``yaw`` as for
entities). The plugin spawns them when it is registered and again after ``sim.reset()``.
Missions use the stations directly (``await plugin["dispenser_1"].dispense(robot)``); the
plugin's own ``dispense`` / ``ingest`` queue the actions without a mission, as the reference
plugin's methods of the same names do.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from fleet_async.core.devices.workcell import (
    DispenseAction,
    IngestAction,
    Workcell,
    WorkcellParams,
)
from fleet_async.core.sim.plugins import SimPlugin

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["WorkcellPlugin"]

_STATION_KEYS = (*WorkcellParams.field_names(), "pose", "yaw", "position")


class WorkcellPlugin(SimPlugin):
    """Spawns and keeps the workcells of a scenario; see the module docstring.

    Raises:
        ValueError: for an unknown config key (naming it and the valid ones) or a bad station.
    """

    def __init__(self, sim_core: SimulationKernel, config: dict[str, Any] | None = None) -> None:
        super().__init__(sim_core, config)
        config = dict(self.config)
        stations = config.pop("workcells", {})
        if not isinstance(stations, dict):
            raise ValueError(
                f"workcell.workcells: expected a mapping of stations, got {stations!r}"
            )
        self._check_keys(config, "workcell config")
        self._specs: dict[str, dict[str, Any]] = {}
        for name, entry in stations.items():
            if not isinstance(entry, dict):
                raise ValueError(f"workcell.workcells.{name}: expected a mapping, got {entry!r}")
            self._check_keys(entry, f"workcell.workcells.{name}")
            spec = {**config, **entry, "name": str(name)}
            if "position" in spec:
                position = list(spec.pop("position"))
                spec["pose"] = position + [0.0] * (3 - len(position))
            WorkcellParams.from_dict(dict(spec))  # every station checked before any spawns
            self._specs[str(name)] = spec
        self._stations: dict[str, Workcell] = {}

    @staticmethod
    def _check_keys(mapping: dict[str, Any], label: str) -> None:
        unknown = sorted(set(mapping) - set(_STATION_KEYS))
        if unknown:
            raise ValueError(
                f"{label}: unknown key(s) {unknown}; valid: {sorted(_STATION_KEYS)} "
                "(and 'workcells' at the top)"
            )

    def on_init(self) -> None:
        """Spawn the stations."""
        self._spawn()

    def on_reset(self) -> None:
        """The reset removed the stations: spawn them again."""
        self._spawn()

    def _spawn(self) -> None:
        self._stations = {}
        for name, spec in self._specs.items():
            station = Workcell.from_dict(dict(spec), self.sim_core)
            assert isinstance(station, Workcell)
            self._stations[name] = station

    # ----- access -------------------------------------------------------------------------

    @property
    def workcells(self) -> dict[str, Workcell]:
        """Stations by name."""
        return dict(self._stations)

    def __getitem__(self, name: str) -> Workcell:
        return self.workcell(name)

    def workcell(self, name: str) -> Workcell:
        """The station called ``name``.

        Raises:
            KeyError: naming the known stations.
        """
        try:
            return self._stations[name]
        except KeyError:
            raise KeyError(f"no workcell {name!r}; workcells: {sorted(self._stations)}") from None

    def get_workcell_position(self, name: str) -> tuple[float, float, float] | None:
        """(x, y, z) of the station called ``name``, or None."""
        station = self._stations.get(name)
        if station is None:
            return None
        x, y, z = station.get_pose().position.tolist()
        return (x, y, z)

    def dispense(self, workcell_name: str, robot: Agent) -> DispenseAction:
        """Queue a dispense at ``workcell_name`` for ``robot`` (no mission needed)."""
        return self.workcell(workcell_name).request_dispense(robot)

    def ingest(self, workcell_name: str, robot: Agent) -> IngestAction:
        """Queue an ingest at ``workcell_name`` from ``robot`` (no mission needed)."""
        return self.workcell(workcell_name).request_ingest(robot)
