"""Joint control and inverse kinematics for URDF agents (arms, mobile manipulators).

``AgentJointsApi`` is a mixin of :class:`~fleet_async.core.agents.agent.Agent` holding the reference
API's joint surface: joint state by index / name, joint targets (one, all, a list or a dict),
convergence checks with per-joint tolerances, and end-effector control through IK. Setting a
target is fire-and-forget: the joints move in the following steps' motion phase (see
``motion/joints.py``); ``JointAction`` / ``PoseAction`` wait for them.

Joint tolerance resolution (``tolerance`` arguments and ``joint_tolerance``): a float applies to
every joint, a list is indexed by joint index, a dict maps joint names to values (joints it
does not name use the class default, 0.01); ``None`` means the agent's ``joint_tolerance``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, ClassVar, cast

import numpy as np

from fleet_async.core.actions.action import DEFAULT_EE_TOLERANCE, DEFAULT_MAX_FORCE
from fleet_async.core.motion.ik import IKParams, detect_end_effector, orientation_error, solve_ik
from fleet_async.core.motion.joints import (
    JointSet,
    JointTargets,
    ToleranceSpec,
    check_tolerance_spec,
    read_joint_infos,
)
from fleet_async.core.world.links import link_index

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.agents.host import AgentHost

__all__ = ["AgentJointsApi"]


class AgentJointsApi:
    """Joint state, joint targets and IK (mixed into Agent)."""

    _KINEMATIC_JOINT_FALLBACK_VELOCITY: ClassVar[float] = 2.0
    """rad/s for revolute joints whose URDF velocity limit is 0 or missing."""
    _KINEMATIC_PRISMATIC_FALLBACK_VELOCITY: ClassVar[float] = 0.5
    """m/s for prismatic joints whose URDF velocity limit is 0 or missing."""
    _DEFAULT_JOINT_TOLERANCE: ClassVar[float] = 0.01
    """rad or m: default joint tolerance."""

    # Provided by Agent / SimObject.
    body_id: int
    urdf_path: str | None
    sim_core: AgentHost | None
    _ik_params: IKParams | None
    _joint_tolerance: ToleranceSpec
    _joint_set: JointSet | None

    @property
    def _agent(self) -> Agent:
        """This object as the Agent it is mixed into (for collaborators that take an Agent)."""
        return cast("Agent", self)

    # ----- the joint set ------------------------------------------------------------------

    def is_urdf_robot(self) -> bool:
        """Whether the agent was loaded from a URDF (and so may have joints)."""
        return self.urdf_path is not None

    @property
    def joints(self) -> JointSet:
        """The agent's joints (built on first use).

        Raises:
            ValueError: for an agent that is not a URDF robot or not in a simulation.
        """
        if self._joint_set is None:
            sim = self.sim_core
            if not self.is_urdf_robot() or sim is None:
                raise ValueError(f"{self!r} has no joints (not a URDF robot in a simulation)")
            # This robot's body only (sim.client would load every robot still waiting).
            body, client = self.body_id, sim.world.client
            infos = read_joint_infos(
                body,
                client,
                self._KINEMATIC_JOINT_FALLBACK_VELOCITY,
                self._KINEMATIC_PRISMATIC_FALLBACK_VELOCITY,
            )
            # Massless robots (mass=0 at spawn) and every robot without physics are kinematic.
            kinematic = not sim.params.physics or all(
                sim.body_mass(body, link) == 0.0 for link in range(-1, len(infos))
            )
            self._joint_set = JointSet(body, client, kinematic, infos, repr(self))
        return self._joint_set

    def get_num_joints(self) -> int:
        """Number of joints (0 for mesh and virtual agents)."""
        if not self.is_urdf_robot() or self.sim_core is None:
            return 0
        return len(self.joints)

    @property
    def joint_names(self) -> list[str]:
        """Joint names in index order ([] for mesh and virtual agents)."""
        return self.joints.names if self.get_num_joints() else []

    @property
    def ik_params(self) -> IKParams:
        """IK solver settings (the defaults unless given at spawn)."""
        if self._ik_params is None:
            self._ik_params = IKParams()
        return self._ik_params

    @property
    def joint_tolerance(self) -> float | list[float] | dict[str, float]:
        """Default joint tolerance (the class default 0.01 when unset)."""
        tol = self._joint_tolerance
        if tol is None:
            return self._DEFAULT_JOINT_TOLERANCE
        return cast("float | list[float] | dict[str, float]", tol)

    @joint_tolerance.setter
    def joint_tolerance(self, value: ToleranceSpec) -> None:
        check_tolerance_spec(value, "joint_tolerance")
        self._joint_tolerance = value

    def resolve_joint_tolerance(self, tolerance: ToleranceSpec, joint: int | str) -> float:
        """The tolerance (rad or m) that ``tolerance`` gives joint ``joint`` (None: the default)."""
        joints = self.joints
        spec = self.joint_tolerance if tolerance is None else tolerance
        return joints.tolerance_for(spec, joints.index(joint), self._DEFAULT_JOINT_TOLERANCE)

    # ----- state --------------------------------------------------------------------------

    def get_joint_state(self, joint_index: int) -> tuple[float, float]:
        """(position, velocity) of one joint (rad, rad/s or m, m/s).

        Kinematic joints report the velocity of the last step's motion.
        """
        joints = self.joints
        return joints.state(joints.index(joint_index))

    def get_joint_state_by_name(self, joint_name: str) -> tuple[float, float]:
        """(position, velocity) of the joint named ``joint_name``.

        Raises:
            ValueError: for an unknown name (listing the joint names).
        """
        joints = self.joints
        return joints.state(joints.index(joint_name))

    def get_all_joints_state(self) -> list[tuple[float, float]]:
        """(position, velocity) of every joint, in index order."""
        joints = self.joints
        return [joints.state(j) for j in range(len(joints))]

    def get_all_joints_state_by_name(self) -> dict[str, tuple[float, float]]:
        """{joint name: (position, velocity)} for every joint."""
        joints = self.joints
        return {info.name: joints.state(info.index) for info in joints.infos}

    def get_joints_state_by_name(
        self, joint_names: Sequence[str]
    ) -> dict[str, tuple[float, float]]:
        """{joint name: (position, velocity)} for the named joints."""
        joints = self.joints
        return {name: joints.state(joints.index(name)) for name in joint_names}

    # ----- targets ------------------------------------------------------------------------

    def set_joint_target(
        self, joint_index: int | str, target_position: float, max_force: float = DEFAULT_MAX_FORCE
    ) -> None:
        """Command one joint (rad or m; clamped to its limits). It moves from the next step."""
        joints = self.joints
        joints.set_target(joints.index(joint_index), target_position, max_force)
        self._activate_joints()

    def set_joint_target_by_name(
        self, joint_name: str, target_position: float, max_force: float = DEFAULT_MAX_FORCE
    ) -> None:
        """Command the joint named ``joint_name``."""
        self.set_joint_target(joint_name, target_position, max_force)

    def set_all_joints_targets(
        self, target_positions: Sequence[float], max_force: float = DEFAULT_MAX_FORCE
    ) -> None:
        """Command every joint at once.

        ``target_positions`` has one value per joint (fixed joints' values are ignored) or one
        per movable joint (revolute / prismatic, in index order).

        Raises:
            ValueError: for a list of any other length.
        """
        self._apply_targets(self._targets_from_list(target_positions), max_force)

    def set_joints_targets_by_name(
        self, joint_targets: Mapping[str, float], max_force: float = DEFAULT_MAX_FORCE
    ) -> None:
        """Command the named joints ({name: position}); the others keep their targets."""
        joints = self.joints
        self._apply_targets({joints.index(n): v for n, v in joint_targets.items()}, max_force)

    def set_joints_targets(
        self, targets: JointTargets, max_force: float = DEFAULT_MAX_FORCE
    ) -> None:
        """Command joints from a list (as ``set_all_joints_targets``) or a {name: position} dict."""
        self._apply_targets(self.joint_targets_map(targets), max_force)

    def joint_targets_map(self, targets: JointTargets) -> dict[int, float]:
        """{joint index: position} from a list or a {name or index: position} mapping."""
        joints = self.joints
        if isinstance(targets, Mapping):
            return {joints.index(k): v for k, v in targets.items()}
        return self._targets_from_list(targets)

    def _targets_from_list(self, values: Sequence[float]) -> dict[int, float]:
        joints = self.joints
        values = list(values)
        movable = joints.movable_indices
        if len(values) == len(joints):
            return {j: values[j] for j in movable}
        if len(values) == len(movable):
            return dict(zip(movable, values, strict=True))
        raise ValueError(
            f"{self!r}: expected {len(joints)} joint targets (one per joint) or {len(movable)} "
            f"(one per movable joint), got {len(values)}"
        )

    def _apply_targets(self, targets: Mapping[int, float], max_force: float) -> None:
        joints = self.joints
        for j, value in targets.items():
            joints.set_target(j, value, max_force)
        if targets:
            self._activate_joints()

    def stop_joints(self) -> None:
        """Hold every joint where it is now (no-op for agents without joints)."""
        if self.get_num_joints():
            self.joints.hold()

    def _activate_joints(self) -> None:
        if self.sim_core is not None:
            self.sim_core.joint_motion.activate(self._agent, self.joints)

    # ----- convergence --------------------------------------------------------------------

    def is_joint_at_target(
        self, joint_index: int, target: float, tolerance: ToleranceSpec = None
    ) -> bool:
        """Whether one joint is within its tolerance of ``target``."""
        return self._within({self.joints.index(joint_index): target}, tolerance)

    def is_joint_at_target_by_name(
        self, joint_name: str, target: float, tolerance: ToleranceSpec = None
    ) -> bool:
        """Whether the named joint is within its tolerance of ``target``."""
        return self._within({self.joints.index(joint_name): target}, tolerance)

    def are_all_joints_at_targets(
        self, target_positions: Sequence[float] | None = None, tolerance: ToleranceSpec = None
    ) -> bool:
        """Whether every joint is at ``target_positions`` (None: the last commanded targets)."""
        if target_positions is None:
            return self._within(self._commanded(), tolerance)
        return self._within(self._targets_from_list(target_positions), tolerance)

    def are_joints_at_targets_by_name(
        self, joint_targets: Mapping[str, float], tolerance: ToleranceSpec = None
    ) -> bool:
        """Whether every named joint is at its target ({name: position})."""
        joints = self.joints
        return self._within({joints.index(n): v for n, v in joint_targets.items()}, tolerance)

    def are_joints_at_targets(
        self, targets: JointTargets | None = None, tolerance: ToleranceSpec = None
    ) -> bool:
        """Whether joints are at ``targets`` (a list, a dict, or None: the last commanded)."""
        if targets is None:
            return self._within(self._commanded(), tolerance)
        return self._within(self.joint_targets_map(targets), tolerance)

    def _commanded(self) -> dict[int, float]:
        joints = self.joints
        return {int(j): float(joints.targets[j]) for j in np.flatnonzero(~np.isnan(joints.targets))}

    def _within(self, targets: Mapping[int, float], tolerance: ToleranceSpec) -> bool:
        spec = self.joint_tolerance if tolerance is None else tolerance
        return self.joints.within(targets, spec, self._DEFAULT_JOINT_TOLERANCE)

    # ----- end effector -------------------------------------------------------------------

    def resolve_end_effector(self, end_effector_link: int | str | None = None) -> int:
        """The end-effector link index: the one given (index or name), else auto-detected."""
        joints = self.joints
        if end_effector_link is None:
            return detect_end_effector(joints)
        link = link_index(self.body_id, end_effector_link, physics_client_id=joints.client)
        if link < 0:
            raise ValueError(f"{self!r}: the end effector must be a link, not the base")
        return link

    def get_end_effector_pose(
        self, end_effector_link: int | str | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """World (position, orientation [x, y, z, w]) of the end-effector link."""
        sim = self._sim_for("get_end_effector_pose")
        return sim.world.link_pose(self._agent, self.resolve_end_effector(end_effector_link))

    def move_end_effector(
        self,
        target_position: Sequence[float],
        target_orientation: Sequence[float] | None = None,
        end_effector_link: int | str | None = None,
        max_force: float = DEFAULT_MAX_FORCE,
        tolerance: float | None = None,
    ) -> bool:
        """Solve IK for an end-effector target (world frame) and command the joints.

        The best-effort targets are always set, even when the target is out of reach.

        Args:
            target_position: [x, y, z] in m.
            target_orientation: [qx, qy, qz, qw], or None for position only.
            end_effector_link: Link index or name; None auto-detects.
            max_force: Motor force for physics joints (N).
            tolerance: m within which the target counts as reachable
                (default ``ik_params.reachability_tolerance``).

        Returns:
            Whether the solution puts the end effector within ``tolerance`` of the target.
        """
        reach = self.ik_reach(target_position, target_orientation, end_effector_link)
        self._apply_targets(reach.targets, max_force)
        limit = self.ik_params.reachability_tolerance if tolerance is None else float(tolerance)
        return reach.position_error <= limit

    def ik_reach(
        self,
        target_position: Sequence[float],
        target_orientation: Sequence[float] | None = None,
        end_effector_link: int | str | None = None,
    ) -> Any:
        """Solve IK without commanding anything; returns an ``IKSolution``."""
        sim = self._sim_for("move_end_effector")
        position = _vector(target_position, 3, "target_position")
        orientation = (
            None
            if target_orientation is None
            else _vector(target_orientation, 4, "target_orientation")
        )
        ee = self.resolve_end_effector(end_effector_link)
        sim.world.sync_object(self._agent)
        return solve_ik(self.joints, ee, position, orientation, self.ik_params)

    def are_ee_at_target(
        self,
        target_position: Sequence[float],
        target_orientation: Sequence[float] | None = None,
        end_effector_link: int | str | None = None,
        tolerance: float = DEFAULT_EE_TOLERANCE,
        orientation_tolerance: float = 0.15,
    ) -> bool:
        """Whether the end effector is within ``tolerance`` m (and, with an orientation,
        ``1 - |dot| <= orientation_tolerance``) of the target."""
        pos, orn = self.get_end_effector_pose(end_effector_link)
        target = _vector(target_position, 3, "target_position")
        if float(np.linalg.norm(pos - target)) > tolerance:
            return False
        if target_orientation is None:
            return True
        wanted = _vector(target_orientation, 4, "target_orientation")
        return orientation_error(orn, wanted) <= orientation_tolerance

    def update_attached_objects_kinematics(self) -> None:
        """Place everything this agent carries at its parent link now (also done every step)."""
        sim = self._sim_for("update_attached_objects_kinematics")
        sim.attachments.follow_parent(self._agent)

    def _sim_for(self, what: str) -> AgentHost:
        sim = self.sim_core
        if sim is None:
            raise ValueError(f"{what}: {self!r} is not part of a simulation")
        return sim


def _vector(values: Sequence[float], n: int, what: str) -> np.ndarray:
    arr = np.asarray(values, dtype=float).reshape(-1)
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{what}: expected {n} finite numbers, got {values!r}")
    return arr
