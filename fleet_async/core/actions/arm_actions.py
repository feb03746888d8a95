"""JointAction and PoseAction: arm motions as queued actions.

Both command joint targets on their first step and then wait, without polling, for the joints
to arrive: the joint pass wakes the action at the end of every step in which the agent's
joints moved (see ``motion/joints.py``). Like a move, an arm action completes at the end of the
step in which its joints came within tolerance.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from fleet_async.core.actions.action import (
    DEFAULT_EE_TOLERANCE,
    DEFAULT_MAX_FORCE,
    TrackedAction,
    WaitHint,
)
from fleet_async.core.base.reprs import short_repr

if TYPE_CHECKING:
    from fleet_async.core.actions.host import ActingAgent

__all__ = ["JointAction", "PoseAction"]


def _check_force(owner: str, value: Any) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0:
        raise ValueError(f"{owner}.max_force: expected a number >= 0 (N), got {value!r}")


class _ArmAction(TrackedAction):
    """What arm actions share: woken when the joints move; cancelling holds the joints."""

    _polled: bool = False  # physics joints: checked every step (motors settle asymptotically)

    def wait_hint(self) -> WaitHint:
        """Woken when kinematic joints move; polled each step for physics joints."""
        return ("poll", None) if self._polled else ("motion", None)

    def on_cancel(self, agent: ActingAgent) -> None:
        """Cancelled while running: the joints stop where they are."""
        agent.stop_joints()


def _is_finite(value: Any) -> bool:
    real = isinstance(value, numbers.Real) and not isinstance(value, bool)
    return real and math.isfinite(value)


@dataclass(eq=False)
class JointAction(_ArmAction):
    """Move joints to target positions and wait until they are within tolerance.

    Args:
        target_joint_positions: A list (one value per joint, or per movable joint) or a dict
            {joint name: position}; rad for revolute joints, m for prismatic ones.
        max_force: Motor force for physics joints (N).
        tolerance: float, list (per joint index) or dict {joint name: tol}. None resolves the
            agent's ``joint_tolerance`` when the action starts and writes it back here.
    """

    target_joint_positions: Sequence[float] | Mapping[str, float] = field(default_factory=list)
    max_force: float = DEFAULT_MAX_FORCE
    tolerance: float | list[float] | dict[str, float] | None = None
    _targets: dict[int, float] | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        targets = self.target_joint_positions
        if isinstance(targets, (str, bytes)) or not isinstance(targets, (Sequence, Mapping)):
            raise ValueError(
                f"JointAction.target_joint_positions: expected a list or a dict, got {targets!r}"
            )
        if not len(targets):
            raise ValueError("JointAction.target_joint_positions: expected at least one target")
        values = targets.values() if isinstance(targets, Mapping) else targets
        if not all(_is_finite(v) for v in values):
            raise ValueError(
                "JointAction.target_joint_positions: expected finite numbers (rad or m), got "
                f"{short_repr(targets)}"
            )
        _check_force("JointAction", self.max_force)

    def step(self, agent: ActingAgent, dt: float) -> bool:
        """Command the targets on the first call; complete once the joints are within tolerance."""
        if self._targets is None:
            if agent.get_num_joints() == 0:
                return self.fail(f"{agent!r} has no joints")
            self._polled = not agent.joints.kinematic
            if self.tolerance is None:
                self.tolerance = agent.joint_tolerance
            try:
                self._targets = agent.joint_targets_map(self.target_joint_positions)
                agent.set_joints_targets(self.target_joint_positions, self.max_force)
            except (ValueError, TypeError) as exc:
                return self.fail(str(exc))
        # The commanded (clamped) targets are what the joints can reach.
        reached = {j: float(agent.joints.targets[j]) for j in self._targets}
        return agent.are_joints_at_targets(reached, self.tolerance)

    def reset(self) -> None:
        """Forget progress."""
        self._reset_status()
        self._targets = None


@dataclass(eq=False)
class PoseAction(_ArmAction):
    """Move the end effector to a world-frame pose through IK.

    The joints are always sent to the best solution found. Once they have settled (within the
    agent's joint tolerance) the action is COMPLETED if the end effector is within
    ``tolerance`` of the target, else FAILED with the distance it is off by.

    Args:
        target_position: [x, y, z] in m, world frame.
        target_orientation: [qx, qy, qz, qw], or None for position only.
        end_effector_link: Link index or name; None auto-detects.
        max_force: Motor force for physics joints (N).
        tolerance: m, for the reachability check and the final check.
    """

    target_position: Sequence[float] = field(default_factory=list)
    target_orientation: Sequence[float] | None = None
    end_effector_link: int | str | None = None
    max_force: float = DEFAULT_MAX_FORCE
    tolerance: float = DEFAULT_EE_TOLERANCE
    reachable: bool | None = field(default=None, init=False)
    """Whether IK found a solution within ``tolerance`` (None before the action starts)."""
    _started: bool = field(default=False, init=False, repr=False)

    def __post_init__(self) -> None:
        pos = np.asarray(self.target_position, dtype=float).reshape(-1)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise ValueError(
                f"PoseAction.target_position: expected [x, y, z], got {self.target_position!r}"
            )
        if self.target_orientation is not None:
            orn = np.asarray(self.target_orientation, dtype=float).reshape(-1)
            if orn.shape != (4,) or not np.all(np.isfinite(orn)):
                raise ValueError(
                    "PoseAction.target_orientation: expected [qx, qy, qz, qw] or None, "
                    f"got {self.target_orientation!r}"
                )
        tol = self.tolerance
        if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not tol > 0:
            raise ValueError(f"PoseAction.tolerance: expected a number > 0 (m), got {tol!r}")
        _check_force("PoseAction", self.max_force)

    def step(self, agent: ActingAgent, dt: float) -> bool:
        """Solve and command on the first call; judge the pose once the joints settle."""
        if not self._started:
            self._started = True
            if agent.get_num_joints() == 0:
                return self.fail(f"{agent!r} has no joints")
            self._polled = not agent.joints.kinematic
            try:
                self.reachable = agent.move_end_effector(
                    self.target_position,
                    self.target_orientation,
                    self.end_effector_link,
                    self.max_force,
                    self.tolerance,
                )
            except (ValueError, TypeError) as exc:
                return self.fail(str(exc))
        if not agent.are_joints_at_targets():
            return False
        pos, _ = agent.get_end_effector_pose(self.end_effector_link)
        off = float(np.linalg.norm(pos - np.asarray(self.target_position, dtype=float)))
        if self.reachable and agent.are_ee_at_target(
            self.target_position,
            self.target_orientation,
            self.end_effector_link,
            tolerance=self.tolerance,
        ):
            return True
        return self.fail(
            f"end-effector target {format_position(self.target_position)} is unreachable: the best "
            f"solution stops {off:.3f} m from it (tolerance {self.tolerance} m)"
        )

    def reset(self) -> None:
        """Forget progress."""
        self._reset_status()
        self._started = False
        self.reachable = None


def format_position(values: Any) -> str:
    """[x, y, z] rounded to mm, for messages."""
    return "[" + ", ".join(f"{float(v):.3f}" for v in values) + "]"
