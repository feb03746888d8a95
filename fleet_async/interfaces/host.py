"""What the fleet interface needs of the simulation and of a robot (narrow protocols).

The fleet interface is handed a simulation that satisfies :class:`ServingHost` and robots that
satisfy :class:`ServedAgent`; ``MultiRobotSimulationCore`` and ``Agent`` do. Naming only these
members keeps the interface readable without the simulation's hundred others, and lets a test
drive it with a small stand-in.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol

from fleet_async.core.actions.action import Action
from fleet_async.core.geometry.pose import Pose

__all__ = ["ServedAgent", "ServingHost"]


class ServedAgent(Protocol):
    """The members of a robot a served vehicle uses."""

    name: str | None
    external_driver: str | None
    motion_result: bool | None

    def get_pose(self) -> Pose: ...
    def set_pose(self, pose: Pose) -> Any: ...
    def set_path(self, path: Any, auto_approach: bool = ..., final_orientation_align: bool = ...,
                 direction: Any = ...) -> None: ...  # fmt: skip
    def stop(self) -> None: ...
    def add_action(self, action: Action) -> None: ...
    def get_attached_objects(self) -> Sequence[Any]: ...
    def set_charging(self, charging: bool) -> None: ...

    @property
    def object_id(self) -> int: ...
    @property
    def state_row(self) -> int: ...
    @property
    def is_moving(self) -> bool: ...
    @property
    def current_waypoint_index(self) -> int: ...
    @property
    def motion_mode(self) -> Any: ...
    @property
    def velocity(self) -> Any: ...
    @property
    def angular_velocity(self) -> float: ...
    @property
    def battery_soc(self) -> float: ...
    @property
    def is_charging(self) -> bool: ...
    @property
    def battery_plugin(self) -> Any: ...


class ServingHost(Protocol):
    """The members of a simulation the fleet interface uses."""

    @property
    def step_count(self) -> int: ...
    @property
    def sim_time(self) -> float: ...
    @property
    def params(self) -> Any: ...
    @property
    def events(self) -> Any: ...
    @property
    def agents(self) -> Sequence[Any]: ...
    @property
    def objects(self) -> Sequence[Any]: ...
    @property
    def fleet(self) -> Any: ...
    @property
    def state(self) -> Any: ...
    @property
    def tracer(self) -> Any: ...

    def add_step_observer(self, observer: Callable[[int], None]) -> None: ...
    def remove_step_observer(self, observer: Callable[[int], None]) -> bool: ...


if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.simulation import MultiRobotSimulationCore

    def _the_real_classes_satisfy_the_protocols(
        sim: MultiRobotSimulationCore, agent: Agent
    ) -> tuple[ServingHost, ServedAgent]:
        return sim, agent  # mypy checks the simulation and Agent against both protocols
