"""Inverse kinematics: a multi-seed iterative solver on pybullet.calculateInverseKinematics.

PyBullet's solver is local: from a poor starting configuration it can stop far from a target
that is reachable. :func:`solve_ik` therefore starts from the current configuration and from
one rest pose per ``IKParams.seed_quartiles`` entry (each joint at ``lower + q * range``),
refines each start up to ``max_outer_iterations`` times (solve, set the joints, measure the
end-effector by forward kinematics), and keeps the configuration whose end effector lands
closest to the target. Joints outside the solvable set are locked at their current position.

The solver moves the body's joints in PyBullet while it searches and puts them back before
returning, so the caller's joint state is untouched.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pybullet as p

from fleet_async.core.motion.joints import JointSet

__all__ = ["IKParams", "IKSolution", "detect_end_effector", "solvable_joints", "solve_ik"]

# Link names that usually mark a tool frame, most specific first.
_EE_NAME_HINTS = (
    "grasptarget",
    "end_effector",
    "ee_link",
    "tcp",
    "tool0",
    "tool",
    "gripper",
    "hand",
)
# Range used for seeding and null-space limits of joints without limits (continuous).
_UNLIMITED = (-math.pi, math.pi)


@dataclass
class IKParams:
    """Inverse-kinematics solver settings (multi-seed, iterative).

    Attributes:
        max_outer_iterations: Refinement iterations per seed.
        convergence_threshold: m; accept a solution this close early.
        max_inner_iterations: ``maxNumIterations`` for pybullet.calculateInverseKinematics.
        residual_threshold: ``residualThreshold`` for pybullet.calculateInverseKinematics.
        reachability_tolerance: m; ``move_end_effector`` reports reachable within this.
        seed_quartiles: Joint-range fractions for the rest-pose seeds.
        ik_joint_names: Joints IK may move (others locked); None = automatic.
    """

    max_outer_iterations: int = 5
    convergence_threshold: float = 0.01
    max_inner_iterations: int = 200
    residual_threshold: float = 0.0001
    reachability_tolerance: float = 0.02
    seed_quartiles: tuple[float, ...] = (0.25, 0.5, 0.75)
    ik_joint_names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        for name in ("max_outer_iterations", "max_inner_iterations"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"IKParams.{name}: expected an integer >= 1, got {value!r}")
        for name in ("convergence_threshold", "residual_threshold", "reachability_tolerance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
                raise ValueError(f"IKParams.{name}: expected a number > 0, got {value!r}")
        quartiles = tuple(float(q) for q in self.seed_quartiles)
        if not quartiles or not all(0.0 <= q <= 1.0 for q in quartiles):
            raise ValueError(
                "IKParams.seed_quartiles: expected fractions in [0, 1], "
                f"got {self.seed_quartiles!r}"
            )
        self.seed_quartiles = quartiles
        if self.ik_joint_names is not None:
            self.ik_joint_names = tuple(str(n) for n in self.ik_joint_names)


class IKSolution(NamedTuple):
    """What :func:`solve_ik` found.

    Attributes:
        targets: {joint index: position} for every joint the solver may move.
        position_error: m from the end effector (at ``targets``) to the target position.
        orientation_error: ``1 - |dot|`` of the reached and target quaternions (0 without one).
    """

    targets: dict[int, float]
    position_error: float
    orientation_error: float


def detect_end_effector(joints: JointSet) -> int:
    """Guess the end-effector link: a tool-like name, else the end of the longest movable chain.

    Raises:
        ValueError: if the body has no links.
    """
    if not len(joints):
        raise ValueError(f"{joints.owner}: has no links, so no end effector")
    names = [info.link_name.lower() for info in joints.infos]
    for hint in _EE_NAME_HINTS:
        for j, name in enumerate(names):
            if hint in name:
                return j
    parents = [
        p.getJointInfo(joints.body_id, j, physicsClientId=joints.client)[16]
        for j in range(len(joints))
    ]

    def depth(j: int) -> int:
        d = 0
        while j >= 0:
            d += int(joints.infos[j].is_movable)
            j = parents[j]
        return d

    return max(range(len(joints)), key=lambda j: (depth(j), j))


def solvable_joints(joints: JointSet, params: IKParams) -> list[int]:
    """Joint indices IK may move: ``params.ik_joint_names``, else every non-continuous one.

    Raises:
        ValueError: for a name that is not a movable joint of the body.
    """
    if params.ik_joint_names is None:
        return [i.index for i in joints.infos if i.is_movable and not i.is_continuous]
    free = []
    for name in params.ik_joint_names:
        j = joints.index(name)
        if not joints.infos[j].is_movable:
            raise ValueError(f"{joints.owner}: IKParams.ik_joint_names: {name!r} is a fixed joint")
        free.append(j)
    return sorted(free)


def _limits(joints: JointSet, free: list[int], dofs: list[int]) -> tuple[list[float], ...]:
    lower, upper, ranges, current = [], [], [], joints.positions
    for j in dofs:
        lo, hi = float(joints.lower[j]), float(joints.upper[j])
        if not math.isfinite(lo):
            lo, hi = current[j] + _UNLIMITED[0], current[j] + _UNLIMITED[1]
        if j not in free:
            lo = hi = float(current[j])
        lower.append(lo)
        upper.append(hi)
        ranges.append(max(hi - lo, 1e-6))
    return lower, upper, ranges


def _seeds(
    joints: JointSet, free: list[int], dofs: list[int], quartiles: Sequence[float]
) -> Iterator[list[float]]:
    current = [float(joints.positions[j]) for j in dofs]
    yield current
    for q in quartiles:
        seed = list(current)
        for k, j in enumerate(dofs):
            if j in free:
                lo, hi = float(joints.lower[j]), float(joints.upper[j])
                if not math.isfinite(lo):
                    lo, hi = _UNLIMITED
                seed[k] = lo + q * (hi - lo)
        yield seed


def solve_ik(
    joints: JointSet,
    ee_link: int,
    target_position: Sequence[float] | np.ndarray,
    target_orientation: Sequence[float] | np.ndarray | None,
    params: IKParams,
) -> IKSolution:
    """Search for joint positions that put link ``ee_link`` at the target (world frame).

    The body's base pose must already be in PyBullet (the caller syncs it).
    """
    free = solvable_joints(joints, params)
    dofs = joints.movable_indices
    lower, upper, ranges = _limits(joints, free, dofs)
    target = np.asarray(target_position, dtype=float)
    orn = None if target_orientation is None else [float(v) for v in target_orientation]
    saved = {j: float(joints.positions[j]) for j in dofs}
    best: IKSolution | None = None
    try:
        for seed in _seeds(joints, free, dofs, params.seed_quartiles):
            found = _refine(
                joints, ee_link, target, orn, params, free, dofs, seed, lower, upper, ranges
            )
            if best is None or (found.position_error, found.orientation_error) < (
                best.position_error,
                best.orientation_error,
            ):
                best = found
            if best.position_error <= params.convergence_threshold and (
                orn is None or best.orientation_error <= 1e-3
            ):
                break
    finally:
        _set(joints, saved)
    assert best is not None
    return best


def _refine(
    joints: JointSet,
    ee_link: int,
    target: np.ndarray,
    orn: list[float] | None,
    params: IKParams,
    free: list[int],
    dofs: list[int],
    seed: list[float],
    lower: list[float],
    upper: list[float],
    ranges: list[float],
) -> IKSolution:
    current = dict(zip(dofs, seed, strict=True))
    _set(joints, current)
    best = _measure(joints, ee_link, target, orn, current)
    for _ in range(params.max_outer_iterations):
        extra = {} if orn is None else {"targetOrientation": orn}
        raw = p.calculateInverseKinematics(
            joints.body_id,
            ee_link,
            target.tolist(),
            lowerLimits=lower,
            upperLimits=upper,
            jointRanges=ranges,
            restPoses=[current[j] for j in dofs],
            maxNumIterations=params.max_inner_iterations,
            residualThreshold=params.residual_threshold,
            physicsClientId=joints.client,
            **extra,
        )
        for k, j in enumerate(dofs):
            if j in free:
                current[j] = min(max(float(raw[k]), float(joints.lower[j])), float(joints.upper[j]))
        _set(joints, current)
        found = _measure(joints, ee_link, target, orn, current)
        if (found.position_error, found.orientation_error) < (
            best.position_error,
            best.orientation_error,
        ):
            best = found
        if best.position_error <= params.convergence_threshold:
            break
    return IKSolution({j: v for j, v in best.targets.items() if j in free}, *best[1:])


def _set(joints: JointSet, values: dict[int, float]) -> None:
    for j, value in values.items():
        p.resetJointState(joints.body_id, j, value, physicsClientId=joints.client)


def _measure(
    joints: JointSet,
    ee_link: int,
    target: np.ndarray,
    orn: list[float] | None,
    current: dict[int, float],
) -> IKSolution:
    state = p.getLinkState(
        joints.body_id, ee_link, computeForwardKinematics=1, physicsClientId=joints.client
    )
    err = float(np.linalg.norm(np.asarray(state[4]) - target))
    orn_err = 0.0 if orn is None else orientation_error(state[5], orn)
    return IKSolution(dict(current), err, orn_err)


def orientation_error(a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray) -> float:
    """``1 - |dot(a, b)|`` of two unit quaternions: 0 when equal (or antipodal)."""
    return float(1.0 - abs(float(np.dot(np.asarray(a, float), np.asarray(b, float)))))
