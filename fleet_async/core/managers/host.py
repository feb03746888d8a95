"""What the managers need of the simulation they are registered with.

A manager spawns agents and objects into the simulation (so it hands it on as their
``AgentHost``), registers itself and finds managers by name, schedules its per-step callback,
draws from the simulation's generator and reads poses in bulk: the kernel satisfies
``ManagerHost``. ``AgentManager.setup_camera`` also frames the GUI camera on its agents
(``CameraHost``), which only ``MultiRobotSimulationCore`` can, through the view floor's mixin.
This floor imports nothing above it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol

from fleet_async.core.agents.host import AgentHost

if TYPE_CHECKING:
    import numpy as np

__all__ = ["CameraHost", "ManagerHost"]


class ManagerHost(AgentHost, Protocol):
    """The simulation, as its managers see it."""

    @property
    def rng(self) -> np.random.Generator: ...

    def register_manager(self, manager: Any) -> None: ...

    def get_manager(self, name: str) -> Any | None: ...

    def register_callback(
        self, callback: Callable[[Any, float], Any], frequency: float | None = None
    ) -> None: ...

    def get_poses(self, object_ids: Sequence[int]) -> tuple[np.ndarray, np.ndarray]: ...


class CameraHost(Protocol):
    """The simulation's GUI camera (``AgentManager.setup_camera`` frames it on the manager's
    agents); the view floor's ``GuiApi`` adds it to ``MultiRobotSimulationCore``."""

    def setup_camera(
        self,
        camera_config: dict[str, Any] | None = None,
        entity_positions: Sequence[Sequence[float]] | None = None,
    ) -> Any: ...
