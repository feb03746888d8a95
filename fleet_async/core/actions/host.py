"""What the actions need of the agent they run on, and of the simulation it is in.

An action is handed its agent at every call (``execute(agent, dt)``) and reads only these
members of it: its id and event bus, its motion (paths, whether it moves, why it cannot),
its joints and end effector, what it carries, and its action queue. Of the simulation, an
action reads the sim time, the action queues' clock (``action_time``: the exact time a
timed action ends on, also inside a step) and the objects (to find what to pick); the action
queue reads the sim time and the event bus. ``Agent`` satisfies ``ActingAgent`` and
``MultiRobotSimulationCore`` satisfies ``ActionHost`` and ``QueueHost``; this floor imports
neither.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    import numpy as np

    from fleet_async.core.actions.action import Action
    from fleet_async.core.base.events import EventBus
    from fleet_async.core.base.types import MovementDirection
    from fleet_async.core.bodies.sim_object import SimObject
    from fleet_async.core.geometry.pose import Pose
    from fleet_async.core.geometry.waypoints import Path
    from fleet_async.core.motion.joints import JointSet, JointTargets, ToleranceSpec

__all__ = ["ActingAgent", "ActionHost", "QueueHost"]


class QueueHost(Protocol):
    """The simulation, as the action queue sees it: the clock and the event bus."""

    @property
    def sim_time(self) -> float: ...

    @property
    def events(self) -> EventBus: ...


class ActionHost(Protocol):
    """The simulation, as an action sees it."""

    @property
    def sim_time(self) -> float: ...

    @property
    def action_time(self) -> float: ...

    @property
    def sim_objects(self) -> list[SimObject]: ...


class ActingAgent(Protocol):
    """An agent, as the actions and the action queue see it."""

    use_fixed_base: bool
    motion_result: bool | None

    @property
    def object_id(self) -> int: ...

    @property
    def sim_core(self) -> ActionHost | None: ...

    def set_charging(self, charging: bool) -> None: ...

    @property
    def motion_blocker(self) -> str | None: ...

    @property
    def is_moving(self) -> bool: ...

    def get_num_joints(self) -> int: ...

    def are_joints_at_targets(
        self, targets: JointTargets | None = None, tolerance: ToleranceSpec = None
    ) -> bool: ...

    def stop_joints(self) -> None: ...

    def set_path(
        self,
        path: Path | Sequence[Pose] | Pose,
        auto_approach: bool = True,
        final_orientation_align: bool = True,
        direction: MovementDirection | str | None = None,
    ) -> None: ...

    def set_joints_targets(self, targets: JointTargets, max_force: float = 500.0) -> None: ...

    @property
    def joints(self) -> JointSet: ...

    def joint_targets_map(self, targets: JointTargets) -> dict[int, float]: ...

    def has_event_bus(self) -> bool: ...

    def get_pose(self) -> Pose: ...

    @property
    def events(self) -> EventBus: ...

    def detach_object(
        self, obj: SimObject, drop_pose: Pose | None = None, drop_relative_pose: Pose | None = None
    ) -> bool: ...

    def submit(self, action: Action) -> Any: ...

    def stop(self) -> None: ...

    def move_end_effector(
        self,
        target_position: Sequence[float],
        target_orientation: Sequence[float] | None = None,
        end_effector_link: int | str | None = None,
        max_force: float = 500.0,
        tolerance: float | None = None,
    ) -> bool: ...

    @property
    def joint_tolerance(self) -> float | list[float] | dict[str, float]: ...

    def ik_reach(
        self,
        target_position: Sequence[float],
        target_orientation: Sequence[float] | None = None,
        end_effector_link: int | str | None = None,
    ) -> Any: ...

    def get_end_effector_pose(
        self, end_effector_link: int | str | None = None
    ) -> tuple[np.ndarray, np.ndarray]: ...

    def get_attached_objects(self) -> list[SimObject]: ...

    def attach_object(
        self,
        obj: SimObject,
        parent_link_index: int | str = -1,
        relative_pose: Pose | None = None,
        joint_type: int = 4,
        keep_world_pose: bool = False,
    ) -> bool: ...

    def are_ee_at_target(
        self,
        target_position: Sequence[float],
        target_orientation: Sequence[float] | None = None,
        end_effector_link: int | str | None = None,
        tolerance: float = 0.02,
        orientation_tolerance: float = 0.15,
    ) -> bool: ...

    def add_action(self, action: Action) -> None: ...
