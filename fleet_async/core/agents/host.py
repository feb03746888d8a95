"""What agents and the fleet's motion need of the simulation they are in.

An ``Agent`` keeps the simulation it joined (``sim_core``) and asks of it what any object does
(``BodyHost``), what its controllers, actions and mission commands read (``MotionHost``,
``ActionHost``, ``MissionHost``), and the fleet's motion (``fleet``), the joints' motion system
(``joint_motion``), whether a step is running (``in_step``) and the mass of one link
(``body_mass``). ``FleetMotion`` reads the state store, the settings, the clock, whether a step
is running and the event bus (for the action queue it owns). The kernel (so
``MultiRobotSimulationCore``) satisfies both; this floor imports nothing above it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

from fleet_async.core.actions.host import ActionHost, QueueHost
from fleet_async.core.bodies.host import BodyHost
from fleet_async.core.missions.host import MissionHost
from fleet_async.core.motion.host import MotionHost

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.agents.fleet import FleetMotion
    from fleet_async.core.base.params import SimulationParams
    from fleet_async.core.collision.safety import SafetyFields
    from fleet_async.core.motion.joints import JointMotion
    from fleet_async.core.world.state import KinematicState

__all__ = ["AgentHost", "FleetHost"]


class FleetHost(QueueHost, Protocol):
    """The simulation, as the fleet's motion (and the action queue it owns) sees it."""

    @property
    def state(self) -> KinematicState: ...

    @property
    def params(self) -> SimulationParams: ...

    @property
    def in_step(self) -> bool: ...

    @property
    def step_count(self) -> int: ...


class AgentHost(BodyHost, MotionHost, ActionHost, MissionHost, Protocol):
    """The simulation, as its agents see it."""

    @property
    def fleet(self) -> FleetMotion: ...

    @property
    def joint_motion(self) -> JointMotion[Agent]: ...

    @property
    def safety(self) -> SafetyFields: ...

    @property
    def in_step(self) -> bool: ...

    def body_mass(self, body_id: int, link: int = -1) -> float: ...
