"""What the agents' mission commands need of the agent, and of the simulation it is in.

``AgentMissionApi`` is mixed into ``Agent`` and reads only these members of it: whether it left
its simulation, its name, its battery (``charge`` refuses without one), its action queue, and
the simulation's installed mission runtime. ``Agent`` satisfies ``MissionAgent`` and the kernel
(so ``MultiRobotSimulationCore``) satisfies ``MissionHost``; this floor imports neither.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from fleet_async.core.actions.action import Action
    from fleet_async.core.missions.mission_api import MissionRuntime

__all__ = ["MissionAgent", "MissionHost"]


class MissionHost(Protocol):
    """The simulation, as a mission command sees it: the runtime ``fleet_async.run`` installed."""

    @property
    def mission_runtime(self) -> MissionRuntime | None: ...


class MissionAgent(Protocol):
    """An agent, as its mission commands see it."""

    name: str | None

    @property
    def sim_core(self) -> MissionHost | None: ...

    @property
    def battery_plugin(self) -> object | None: ...

    def check_not_removed(self, what: str) -> None: ...

    def add_action(self, action: Action) -> None: ...
