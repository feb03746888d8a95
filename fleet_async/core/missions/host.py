"""What the mission seam needs of the objects above it: the agent, the simulation, the devices.

``AgentMissionApi`` is mixed into ``Agent`` and reads only these members of it: whether it left
its simulation, its name, its battery (``charge`` refuses without one), its action queue, and
the simulation's installed mission runtime. ``Agent`` satisfies ``MissionAgent`` and the kernel
(so ``MultiRobotSimulationCore``) satisfies ``MissionHost``.

``fleet_async.tasks`` (which imports nothing of the core but this seam) annotates with the rest:
``MissionSim`` is what its runtime and driver use of the simulation (the clock, the parameters,
the event bus, stepping, installing the runtime), and ``MissionDoor`` / ``MissionElevator`` are
what its device missions (``door.pass_through``, ``elevator.ride``) call on a door and a lift.
The kernel (so ``MultiRobotSimulationCore``) satisfies ``MissionSim``; ``Door`` and ``Elevator``
satisfy theirs (``core/devices/`` checks it for the type checker). This floor imports none of
them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from fleet_async.core.actions.action import Action
    from fleet_async.core.base.params import SimulationParams
    from fleet_async.core.geometry.pose import Pose
    from fleet_async.core.missions.mission_api import MissionRuntime, SimEventBus

__all__ = [
    "MissionAgent",
    "MissionDevice",
    "MissionDoor",
    "MissionElevator",
    "MissionHost",
    "MissionSim",
]


class MissionHost(Protocol):
    """The simulation, as a mission command sees it: its mission runtime."""

    @property
    def mission_runtime(self) -> MissionRuntime | None: ...

    def ensure_mission_runtime(self) -> MissionRuntime: ...

    @property
    def params(self) -> SimulationParams: ...


class MissionAgent(Protocol):
    """An agent, as its mission commands see it."""

    name: str | None

    @property
    def sim_core(self) -> MissionHost | None: ...

    @property
    def battery_plugin(self) -> object | None: ...

    def check_not_removed(self, what: str) -> None: ...

    def add_action(self, action: Action) -> None: ...


class MissionSim(MissionHost, Protocol):
    """The simulation, as the mission layer drives it (``fleet_async.run`` and its runtime):
    the step count as the missions' clock, ``params.timestep`` / ``target_rtf`` / ``seed``,
    the event bus, one step or a span of provably empty steps, and the runtime slot."""

    @property
    def params(self) -> SimulationParams: ...

    @property
    def step_count(self) -> int: ...

    @property
    def sim_time(self) -> float: ...

    @property
    def events(self) -> SimEventBus: ...

    def step_once(self) -> object: ...

    def idle_steps(self, limit: int) -> int: ...

    def seed_sequence(self, *key: Any) -> Any: ...

    def skip_idle_steps(self, limit: int) -> int: ...

    def set_mission_runtime(self, runtime: MissionRuntime | None) -> None: ...

    def wait_until(self, predicate: Callable[[], bool]) -> Any: ...


class MissionDevice(Protocol):
    """A device shared between missions through a Resource: the simulation it is part of."""

    @property
    def sim_core(self) -> MissionSim | None: ...


class MissionDoor(MissionDevice, Protocol):
    """A door, as ``door.pass_through`` uses it: its commands return the events to await."""

    def open(self, *, detached: bool = ...) -> Any: ...

    def close(self, *, detached: bool = ...) -> Any: ...


class MissionElevator(MissionDevice, Protocol):
    """A lift, as ``elevator.ride`` uses it: its floors, where it is, calling it, a trip."""

    @property
    def name(self) -> str | None: ...

    @property
    def is_moving(self) -> bool: ...

    @property
    def pending_floors(self) -> tuple[str, ...]: ...

    def floor_height(self, floor: str) -> float: ...

    def floor_at(self, z: float) -> str: ...

    def is_at(self, floor: str) -> bool: ...

    def platform_pose(self, floor: str, z_offset: float = ...) -> Pose: ...

    def landing_pose(self, floor: str, z_offset: float = ...) -> Pose: ...

    def go_to(self, floor: str) -> Any: ...

    def queue_trip(self, floor: str) -> Action: ...
