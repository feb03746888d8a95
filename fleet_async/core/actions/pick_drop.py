"""PickAction and DropAction, built on one shared approach / act / retreat sequence.

Both actions run the same stages: drive to an approach pose ``approach_offset`` metres from
the target (facing it), drive to ``pick_offset`` / ``drop_offset`` from it, attach or detach,
and back out to the approach pose. A sub-move shorter than ``move_skip_threshold`` is skipped,
and so are all of them on a fixed-base agent (its goals are ignored). Only what differs lives
in the subclasses: which object is the target, and what "act" does.

With ``joint_targets`` or ``ee_target_position`` (one of them, not both) the act is done by an
arm: the joints reach (the given targets, or an IK solution for the end-effector target) and the
object is attached to or detached from ``attach_link``. The arm stays where the reach took it,
as in pybullet_fleet (queue a ``JointAction`` to fold it away). An arm whose base cannot move
reaches from where it stands, without the drive stages.
"""

from __future__ import annotations

import logging
from collections import deque
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from fleet_async.core.actions.action import (
    DEFAULT_EE_TOLERANCE,
    DEFAULT_MAX_FORCE,
    DEFAULT_MOVE_SKIP_THRESHOLD,
    TrackedAction,
    WaitHint,
)
from fleet_async.core.actions.arm_actions import format_position
from fleet_async.core.base.reprs import short_repr
from fleet_async.core.base.types import DropPhase, MovementDirection, PickPhase
from fleet_async.core.geometry.approach import calculate_offset_pose, find_nearest
from fleet_async.core.geometry.pose import Pose

if TYPE_CHECKING:
    from fleet_async.core.actions.host import ActingAgent
    from fleet_async.core.bodies.sim_object import SimObject

__all__ = ["DropAction", "PickAction"]

logger = logging.getLogger(__name__)

# A stage: ("move", pose, phase, direction) or ("act", callable returning an error or None, phase)
_Stage = tuple[Any, ...]


class _ApproachAction(TrackedAction):
    """Shared machinery of pick and drop: a queue of move / act stages.

    Subclasses are dataclasses that declare the fields (in the reference API's order) and set
    the class variables below; this class holds only behaviour. Fields both actions have:

    Args:
        use_approach: Drive to the approach pose first.
        approach_pose: The approach pose; None computes it ``approach_offset`` short.
        approach_offset: m short of the target where the approach pose is.
        joint_targets: Arm: joint positions to reach with (a list, or {joint name: position});
            not together with ``ee_target_position``.
        joint_tolerance: Arm: rad (or m) within which a joint has arrived.
        joint_max_force: Arm: N (or N m) of the joint motors with physics.
        ee_target_position: Arm: [x, y, z] for the end effector, reached through IK.
        ee_target_orientation: Arm: [qx, qy, qz, qw] for the end effector, or None.
        ee_end_effector_link: Arm: link index or name of the end effector (None: found).
        ee_tolerance: Arm: m within which the end effector has arrived.
        continue_on_ik_failure: Go on with the best IK solution when the target is out of
            reach (else the action fails).
    """

    _phases: ClassVar[type[Enum]] = PickPhase
    _in_offset_field: ClassVar[str] = "pick_offset"
    _verb: ClassVar[str] = "PICK"
    _act_phase: ClassVar[str] = "PICKING"
    use_approach: bool
    approach_pose: Pose | None
    approach_offset: float
    move_skip_threshold: float
    joint_targets: Any
    ee_target_position: Any
    phase: Enum
    _stages: deque[_Stage] | None
    _moving: bool
    _arm_targets: dict[int, float] | None
    joint_tolerance: Any
    joint_max_force: float
    ee_target_orientation: Any
    ee_end_effector_link: Any
    ee_tolerance: float
    continue_on_ik_failure: bool

    def _check_common(self) -> None:
        name = type(self).__name__
        for attr in ("approach_offset", "move_skip_threshold"):
            value = getattr(self, attr)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0:
                raise ValueError(f"{name}.{attr}: expected a number >= 0 (m), got {value!r}")
        if self.approach_pose is not None and not isinstance(self.approach_pose, Pose):
            raise ValueError(
                f"{name}.approach_pose: expected a Pose or None, got {self.approach_pose!r}"
            )
        if self.joint_targets is not None and self.ee_target_position is not None:
            raise ValueError(
                f"{name}: give joint_targets or ee_target_position, not both (got "
                f"joint_targets={short_repr(self.joint_targets)}, "
                f"ee_target_position={short_repr(self.ee_target_position)})"
            )

    # subclass hooks ------------------------------------------------------------------------
    def _target_position(self, agent: ActingAgent) -> np.ndarray | str:
        raise NotImplementedError

    def _act(self, agent: ActingAgent) -> str | None:
        raise NotImplementedError

    # shared sequence -----------------------------------------------------------------------
    def _plan(self, agent: ActingAgent) -> deque[_Stage] | str:
        uses_arm = self.joint_targets is not None or self.ee_target_position is not None
        if uses_arm and agent.get_num_joints() == 0:
            return f"joint_targets / ee_target_* need an agent with joints; {agent!r} has none"
        target = self._target_position(agent)
        if isinstance(target, str):
            return target
        # An arm on a base that cannot move, and any fixed-base agent (whose goals are
        # ignored), acts from where it stands.
        drives = agent.motion_blocker is None or not (uses_arm or agent.use_fixed_base)
        here = agent.get_pose().position
        offset = float(getattr(self, self._in_offset_field))
        inner = calculate_offset_pose(target, here, offset, keep_height=True)
        phases = self._phases
        act_phase = phases[self._act_phase]
        stages: deque[_Stage] = deque()
        approach = None
        if self.use_approach and drives:
            # approach_offset is the approach pose's distance from the target itself.
            approach = self.approach_pose or calculate_offset_pose(
                target, here, float(self.approach_offset), keep_height=True
            )
            stages.append(("move", approach, phases["APPROACHING"], MovementDirection.FORWARD))
        if drives:
            stages.append(
                ("move", inner, phases[f"MOVING_TO_{self._verb}"], MovementDirection.FORWARD)
            )
        if uses_arm:
            stages.append(("joints", self._reach_targets, act_phase))
        stages.append(("act", self._act, act_phase))
        if approach is not None:
            stages.append(("move", approach, phases["RETREATING"], MovementDirection.BACKWARD))
        return stages

    def _reach_targets(self, agent: ActingAgent) -> dict[int, float] | str:
        """Joint targets for the reach: the given ones, or an IK solution for the EE target."""
        if self.joint_targets is not None:
            return agent.joint_targets_map(self.joint_targets)
        solution = agent.ik_reach(
            self.ee_target_position, self.ee_target_orientation, self.ee_end_effector_link
        )
        if solution.position_error > self.ee_tolerance:
            message = (
                f"end-effector target {format_position(self.ee_target_position)} is out of "
                f"reach: the best solution stops {solution.position_error:.3f} m from it "
                f"(ee_tolerance {self.ee_tolerance} m)"
            )
            if not self.continue_on_ik_failure:
                return message
            logger.warning(
                "%r %s: %s; continuing (continue_on_ik_failure)",
                agent,
                type(self).__name__,
                message,
            )
        return dict(solution.targets)

    def _run_joint_stage(self, agent: ActingAgent, stage: _Stage) -> bool | str:
        """Command (first call) and wait for one joint stage; True once the joints arrived."""
        if self._arm_targets is None:
            targets = stage[1](agent)
            if isinstance(targets, str):
                return targets
            try:
                agent.set_joints_targets(targets, self.joint_max_force)
            except (ValueError, TypeError) as exc:
                return str(exc)
            self._arm_targets = {j: float(agent.joints.targets[j]) for j in targets}
        if not agent.are_joints_at_targets(self._arm_targets, self.joint_tolerance):
            return False
        self._arm_targets = None
        return True

    def step(self, agent: ActingAgent, dt: float) -> bool:
        """Run stages until one has to wait for motion, or all are done."""
        if self._stages is None:
            planned = self._plan(agent)
            if isinstance(planned, str):
                return self.fail(planned)
            self._stages = planned
        while self._stages:
            stage = self._stages[0]
            self.phase = stage[2]
            if stage[0] == "act":
                error = stage[1](agent)
                if error is not None:
                    return self.fail(error)
                self._stages.popleft()
                continue
            if stage[0] == "joints":
                arrived = self._run_joint_stage(agent, stage)
                if isinstance(arrived, str):
                    return self.fail(arrived)
                if not arrived:
                    return False
                self._stages.popleft()
                continue
            pose: Pose = stage[1]
            if self._moving:
                if agent.is_moving:
                    return False
                self._moving = False
                if agent.motion_result is False:
                    return self.fail(f"motion stopped during {self.phase.value}")
                self._stages.popleft()
                continue
            if (
                float(np.linalg.norm(agent.get_pose().position - pose.position))
                <= self.move_skip_threshold
            ):
                self._stages.popleft()
                continue
            blocker = agent.motion_blocker
            if blocker is not None:
                return self.fail(f"cannot move to the {self.phase.value} pose: {blocker}")
            agent.set_path([pose], direction=stage[3])
            self._moving = True
            return False
        return True

    def wait_hint(self) -> WaitHint:
        """Waits for motion while a sub-move or the arm runs, else polls."""
        return ("motion", None) if self._moving or self._arm_targets is not None else ("poll", None)

    def on_cancel(self, agent: ActingAgent) -> None:
        """Cancelled while the arm was moving: the joints stop where they are."""
        if self._arm_targets is not None:
            agent.stop_joints()

    def reset(self) -> None:
        """Forget progress."""
        self._reset_status()
        self.phase = self._phases["INIT"]
        self._stages = None
        self._moving = False
        self._arm_targets = None


def _resolve_body(agent: ActingAgent, body_id: Any) -> SimObject | None:
    sim = agent.sim_core
    if sim is None:
        return None
    if hasattr(body_id, "body_id") and hasattr(body_id, "get_pose"):
        return body_id  # a SimObject given directly
    return next((o for o in sim.sim_objects if o.body_id == body_id), None)


@dataclass(eq=False)
class PickAction(_ApproachAction):
    """Pick an object and attach it to the robot.

    Args:
        target_object_id: PyBullet body id (or the SimObject) to pick.
        target_position: Else pick the nearest pickable, unattached object within
            ``search_radius`` of this [x, y, z] (XY distance when ``use_2d_search``).
        search_radius: m.
        use_2d_search: Ignore height when searching.
        pick_offset: m from the object where the robot stops to pick.
        move_skip_threshold: m; shorter sub-moves are skipped.
        attach_link: Robot link index or name (-1 / "base_link": the base).
        attach_relative_pose: Object pose in that link's frame once attached.
    """

    target_object_id: Any = None
    target_position: Any = None
    search_radius: float = 0.5
    use_2d_search: bool = True
    use_approach: bool = True
    approach_pose: Pose | None = None
    approach_offset: float = 1.0
    pick_offset: float = 0.0
    move_skip_threshold: float = DEFAULT_MOVE_SKIP_THRESHOLD
    attach_link: int | str = -1
    attach_relative_pose: Pose = field(default_factory=lambda: Pose([0.0, 0.0, 0.0]))
    joint_targets: Any = None
    joint_tolerance: Any = None
    joint_max_force: float = DEFAULT_MAX_FORCE
    ee_target_position: Any = None
    ee_target_orientation: Any = None
    ee_end_effector_link: Any = None
    ee_tolerance: float = DEFAULT_EE_TOLERANCE
    continue_on_ik_failure: bool = True
    phase: Enum = field(default=PickPhase.INIT, init=False)
    picked_object: SimObject | None = field(default=None, init=False)
    _stages: deque[_Stage] | None = field(default=None, init=False, repr=False)
    _moving: bool = field(default=False, init=False, repr=False)
    _arm_targets: dict[int, float] | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        self._check_common()
        if self.target_object_id is None and self.target_position is None:
            raise ValueError("PickAction: give target_object_id or target_position")
        if not (isinstance(self.search_radius, (int, float)) and self.search_radius > 0):
            raise ValueError(
                f"PickAction.search_radius: expected a number > 0 (m), got {self.search_radius!r}"
            )
        if not isinstance(self.attach_relative_pose, Pose):
            raise ValueError(
                "PickAction.attach_relative_pose: expected a Pose, "
                f"got {self.attach_relative_pose!r}"
            )

    def _target_position(self, agent: ActingAgent) -> np.ndarray | str:
        obj = self._find(agent)
        if isinstance(obj, str):
            return obj
        self.picked_object = obj
        return obj.get_pose().position

    def _find(self, agent: ActingAgent) -> SimObject | str:
        if self.target_object_id is not None:
            obj = _resolve_body(agent, self.target_object_id)
            if obj is None:
                return f"no object with body id {self.target_object_id!r}"
            if not obj.pickable:
                return f"{obj!r} is not pickable"
            if obj.is_attached():
                return f"{obj!r} is already attached to {obj.get_attached_parent()!r}"
            return obj
        sim = agent.sim_core
        assert sim is not None
        found = find_nearest(
            sim.sim_objects,
            list(self.target_position),
            self.search_radius,
            # Robots are never picked by a search; name one by id to pick it on purpose.
            predicate=lambda o: o.pickable and not o.is_agent and not o.is_attached(),
            exclude=agent,
            use_2d=self.use_2d_search,
        )
        if found is None:
            return (
                f"no pickable object within {self.search_radius} m of {list(self.target_position)}"
            )
        return found

    def _act(self, agent: ActingAgent) -> str | None:
        obj = self.picked_object
        assert obj is not None
        if obj.is_attached():  # someone else took it while we were driving
            return (
                f"{obj!r} was attached to {obj.get_attached_parent()!r} before it could be picked"
            )
        try:
            agent.attach_object(
                obj, parent_link_index=self.attach_link, relative_pose=self.attach_relative_pose
            )
        except ValueError as exc:
            return f"attach failed: {exc}"
        return None

    def reset(self) -> None:
        """Forget progress and the picked object."""
        super().reset()
        self.picked_object = None


@dataclass(eq=False)
class DropAction(_ApproachAction):
    """Drop an attached object at ``drop_pose``.

    Args:
        drop_pose: Where the object goes (the robot drives there, ``drop_offset`` short).
        drop_offset: m from ``drop_pose`` where the robot stops.
        move_skip_threshold: m; shorter sub-moves are skipped.
        place_gently: Place exactly at ``drop_pose``; else release ``drop_height`` above it.
        drop_height: m above ``drop_pose`` when not placing gently.
        target_object_id: Body id (or SimObject) to drop; None drops the first attached.
        drop_relative_pose: Instead of ``drop_pose``, offset the object from where it is.
    """

    drop_pose: Pose
    use_approach: bool = True
    approach_pose: Pose | None = None
    approach_offset: float = 1.0
    drop_offset: float = 0.0
    move_skip_threshold: float = DEFAULT_MOVE_SKIP_THRESHOLD
    place_gently: bool = True
    drop_height: float = 0.1
    target_object_id: Any = None
    drop_relative_pose: Pose | None = None
    joint_targets: Any = None
    joint_tolerance: Any = None
    joint_max_force: float = DEFAULT_MAX_FORCE
    ee_target_position: Any = None
    ee_target_orientation: Any = None
    ee_end_effector_link: Any = None
    ee_tolerance: float = DEFAULT_EE_TOLERANCE
    continue_on_ik_failure: bool = True
    phase: Enum = field(default=DropPhase.INIT, init=False)
    dropped_object: SimObject | None = field(default=None, init=False)
    _stages: deque[_Stage] | None = field(default=None, init=False, repr=False)
    _moving: bool = field(default=False, init=False, repr=False)
    _arm_targets: dict[int, float] | None = field(default=None, init=False, repr=False)
    _phases: ClassVar[type[Enum]] = DropPhase
    _in_offset_field: ClassVar[str] = "drop_offset"
    _verb: ClassVar[str] = "DROP"
    _act_phase: ClassVar[str] = "DROPPING"

    def __post_init__(self) -> None:
        self._check_common()
        if not isinstance(self.drop_pose, Pose):
            raise ValueError(f"DropAction.drop_pose: expected a Pose, got {self.drop_pose!r}")
        if self.drop_relative_pose is not None and not isinstance(self.drop_relative_pose, Pose):
            raise ValueError(
                f"DropAction.drop_relative_pose: expected a Pose, got {self.drop_relative_pose!r}"
            )

    def _target_position(self, agent: ActingAgent) -> np.ndarray | str:
        carried = agent.get_attached_objects()
        if not carried:
            return "nothing is attached to drop"
        if self.target_object_id is not None:
            obj = _resolve_body(agent, self.target_object_id)
            if obj is None or obj not in carried:
                return f"object {self.target_object_id!r} is not attached to {agent!r}"
        else:
            obj = carried[0]
        self.dropped_object = obj
        assert self.drop_pose is not None
        return self.drop_pose.position

    def _act(self, agent: ActingAgent) -> str | None:
        obj = self.dropped_object
        assert obj is not None
        assert self.drop_pose is not None
        if obj.get_attached_parent() is not agent:
            return f"{obj!r} is no longer attached to {agent!r}"
        if self.drop_relative_pose is not None:
            agent.detach_object(obj, drop_relative_pose=self.drop_relative_pose)
            return None
        pose = self.drop_pose
        if not self.place_gently:
            pose = Pose(pose.position + np.array([0.0, 0.0, self.drop_height]), pose.orientation)
        agent.detach_object(obj, drop_pose=pose)
        return None

    def reset(self) -> None:
        """Forget progress and the dropped object."""
        super().reset()
        self.dropped_object = None
