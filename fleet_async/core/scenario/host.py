"""What building a scenario needs of the simulation it fills.

Spawning a scenario's entities needs what the managers need (``ManagerHost``, which the kernel
satisfies) and ``unregister_manager``, to leave nothing behind when an entry fails
(``EntityHost``). Building the whole scenario (``build.py``) also keeps the scenario's missions
and ``serve:`` section on the simulation, loads its world (``WorldLoadingApi``, on this floor),
registers plugins, frames the GUI camera, starts a trace (the view floor's mixins) and closes
the simulation when the scenario is bad (``BuiltSim``): only ``MultiRobotSimulationCore`` has
all of that, and ``from_dict`` / ``from_yaml`` return the class they are called on. This floor
imports nothing above it.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol

from fleet_async.core.managers.host import ManagerHost

if TYPE_CHECKING:
    from fleet_async.core.scenario.missions import MissionSpec
    from fleet_async.core.sim.plugins import SimPlugin

__all__ = ["BuiltSim", "EntityHost"]


class EntityHost(ManagerHost, Protocol):
    """The simulation, as spawning a scenario's entities sees it."""

    def unregister_manager(self, manager: Any) -> bool: ...


class BuiltSim(EntityHost, Protocol):
    """The simulation, as building a whole scenario sees it."""

    scenario_missions: tuple[MissionSpec, ...]
    scenario_serve: Mapping[str, Any]

    def load_world(
        self,
        world_config: Mapping[str, Any],
        skip_models: Sequence[str] | None = None,
        *,
        base_dir: str | os.PathLike[str] | None = None,
    ) -> Any: ...

    def register_plugin(
        self,
        plugin_or_cls: SimPlugin | type[SimPlugin],
        config: dict[str, Any] | None = None,
        frequency: float | None = None,
    ) -> SimPlugin: ...

    def setup_camera(
        self,
        camera_config: dict[str, Any] | None = None,
        entity_positions: Sequence[Sequence[float]] | None = None,
    ) -> Any: ...

    def start_trace(
        self,
        path: str | os.PathLike[str] = "run.fatrace",
        every_n_steps: int | None = None,
        *,
        fps: float | None = None,
        flush_seconds: float = 1.0,
    ) -> Any: ...

    def close(self) -> None: ...
