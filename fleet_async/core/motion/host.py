"""What the motion floor needs of an agent, and of the simulation the agent is in.

Controllers are handed an agent at every call (``compute(agent, dt)``, ``on_install``, ...),
but read only these members of it: the built-in ones drive the agent's slot in the kinematic
engine the agent hands them (``motion_engine``, ``motion_slot``); patrol and random walk read
the agent's pose, whether it moves or has an action, the sim time and their random stream
(``rng_for``), and send it a path or a goal. ``Agent`` satisfies ``ControlledAgent`` and
``MultiRobotSimulationCore`` satisfies ``MotionHost``; this floor imports neither.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    import numpy as np

    from fleet_async.core.base.params import SimulationParams
    from fleet_async.core.base.types import MovementDirection
    from fleet_async.core.geometry.pose import Pose
    from fleet_async.core.motion.kinematics import KinematicEngine

__all__ = ["ControlledAgent", "MotionHost", "Numbered"]


class Numbered(Protocol):
    """Anything with an object id (an agent whose joints move)."""

    @property
    def object_id(self) -> int: ...


class MotionHost(Protocol):
    """The simulation, as a controller sees it: the clock, the settings and random streams."""

    @property
    def sim_time(self) -> float: ...

    @property
    def params(self) -> SimulationParams: ...

    def rng_for(self, *key: Any) -> np.random.Generator: ...


class ControlledAgent(Numbered, Protocol):
    """An agent, as its controllers see it."""

    @property
    def sim_core(self) -> MotionHost | None: ...

    @property
    def motion_engine(self) -> KinematicEngine | None: ...

    @property
    def motion_slot(self) -> int: ...

    @property
    def is_moving(self) -> bool: ...

    def get_current_action(self) -> object | None: ...

    def get_pose(self) -> Pose: ...

    def set_path(
        self,
        path: list[Pose],
        auto_approach: bool = True,
        final_orientation_align: bool = True,
        direction: MovementDirection | str | None = None,
    ) -> None: ...

    def set_goal_pose(
        self, goal: Pose, direction: MovementDirection | str | None = None
    ) -> None: ...
