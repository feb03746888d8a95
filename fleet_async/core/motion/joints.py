"""Joint state and joint targets of URDF agents, and the per-step pass that moves them.

A :class:`JointSet` holds one body's joints: their URDF limits, current positions, commanded
targets and motor forces. Kinematic joints (no physics, or a massless robot) move straight
towards their targets at the URDF velocity limit, ``max_velocity * dt`` per step, and land
exactly on the target; the new positions are written to PyBullet so link poses (forward
kinematics) follow. Physics joints are driven by PyBullet's position motors with the given
force and read back from PyBullet.

:class:`JointMotion` is the motion system that advances every agent whose joints are moving,
in ascending object id, and wakes the action each such agent is waiting on.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Generic, TypeVar

import numpy as np
import pybullet as p

from fleet_async.core.base.reprs import short_repr

if TYPE_CHECKING:
    from fleet_async.core.motion.host import Numbered

__all__ = [
    "JointInfo",
    "JointMotion",
    "JointSet",
    "JointTargets",
    "ToleranceSpec",
    "check_tolerance_spec",
]

logger = logging.getLogger(__name__)

A = TypeVar("A", bound="Numbered")
"""The agents whose joints move (``Agent`` in a simulation)."""

ToleranceSpec = float | Sequence[float] | Mapping[str, float] | None
JointTargets = Sequence[float] | Mapping[str, float] | Mapping[int, float]
"""Joint targets: a list, or a mapping keyed by joint name or index."""
"""A joint tolerance: one value for all joints, one per joint index, or {joint name: value}."""

_MOVABLE = (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC)


@dataclass(frozen=True)
class JointInfo:
    """One joint as the URDF defines it.

    Attributes:
        index: Joint index (0-based; also the index of its child link).
        name: Joint name.
        joint_type: PyBullet joint type (``pybullet.JOINT_REVOLUTE``, ``JOINT_PRISMATIC``, ...).
        lower: Lower limit (rad or m); ``-inf`` for continuous joints.
        upper: Upper limit (rad or m); ``+inf`` for continuous joints.
        max_velocity: Velocity limit used to move the joint kinematically (rad/s or m/s).
        max_force: The URDF's effort limit (N or N*m; 0 when the URDF gives none).
        link_name: Name of the joint's child link.
    """

    index: int
    name: str
    joint_type: int
    lower: float
    upper: float
    max_velocity: float
    max_force: float
    link_name: str

    @property
    def is_movable(self) -> bool:
        """Revolute (including continuous) or prismatic: one degree of freedom to control."""
        return self.joint_type in _MOVABLE

    @property
    def is_continuous(self) -> bool:
        """A revolute joint without limits (PyBullet reports lower > upper for those)."""
        return self.joint_type == p.JOINT_REVOLUTE and not math.isfinite(self.lower)


def read_joint_infos(
    body_id: int, client: int, revolute_fallback: float, prismatic_fallback: float
) -> tuple[JointInfo, ...]:
    """Read every joint of a body, with velocity fallbacks where the URDF has no limit."""
    infos = []
    for j in range(p.getNumJoints(body_id, physicsClientId=client)):
        raw = p.getJointInfo(body_id, j, physicsClientId=client)
        jtype, lower, upper = int(raw[2]), float(raw[8]), float(raw[9])
        if jtype == p.JOINT_REVOLUTE and lower > upper:
            lower, upper = -math.inf, math.inf
        velocity = float(raw[11])
        if not velocity > 0:
            velocity = prismatic_fallback if jtype == p.JOINT_PRISMATIC else revolute_fallback
        infos.append(
            JointInfo(
                j,
                raw[1].decode("utf-8"),
                jtype,
                lower,
                upper,
                velocity,
                float(raw[10]),
                raw[12].decode("utf-8"),
            )
        )
    return tuple(infos)


def _finite_tolerance(value: Any) -> bool:
    real = isinstance(value, (int, float, np.number)) and not isinstance(value, bool)
    return real and math.isfinite(value) and value >= 0


def check_tolerance_spec(spec: Any, what: str) -> None:
    """Refuse a tolerance spec (None, a number, a list or a name-keyed mapping) holding a value
    that is not a finite number >= 0, naming ``what`` and the value."""
    if spec is None:
        return
    values = list(spec.values()) if isinstance(spec, Mapping) else spec
    if not isinstance(values, (list, tuple, np.ndarray)):
        values = [values]
    for value in values:
        if not _finite_tolerance(value):
            raise ValueError(
                f"{what}: expected finite numbers >= 0 (rad or m), got {short_repr(value)} "
                f"in {short_repr(spec)}"
            )


class JointSet:
    """The joints of one body: limits, positions, targets.

    Args:
        body_id: PyBullet body id.
        client: PyBullet client id.
        kinematic: Move joints kinematically (True) or with PyBullet motors (False).
        infos: The body's joints (see :func:`read_joint_infos`).
        owner: Name used in error messages (e.g. the agent's repr).
    """

    def __init__(
        self, body_id: int, client: int, kinematic: bool, infos: tuple[JointInfo, ...], owner: str
    ) -> None:
        self.body_id = body_id
        self.client = client
        self.kinematic = kinematic
        self.infos = infos
        self.owner = owner
        self._by_name = {info.name: info.index for info in infos}
        n = len(infos)
        self.positions = np.array(
            [p.getJointState(body_id, j, physicsClientId=client)[0] for j in range(n)], dtype=float
        )
        self.velocities = np.zeros(n)
        self.targets = np.full(n, np.nan)
        """Last commanded target per joint; NaN where none was ever commanded."""
        self.forces = np.zeros(n)
        self.max_velocity = np.array([i.max_velocity for i in infos], dtype=float)
        self.lower = np.array([i.lower for i in infos], dtype=float)
        self.upper = np.array([i.upper for i in infos], dtype=float)
        self.movable = np.array([i.is_movable for i in infos], dtype=bool)
        self.moving = False
        """Some joint has not reached its target yet."""

    def __len__(self) -> int:
        return len(self.infos)

    @property
    def names(self) -> list[str]:
        """Joint names in index order."""
        return [info.name for info in self.infos]

    @property
    def movable_indices(self) -> list[int]:
        """Indices of the revolute and prismatic joints, in order."""
        return [info.index for info in self.infos if info.is_movable]

    def index(self, joint: int | str) -> int:
        """Resolve a joint index or name.

        Raises:
            ValueError: for an index out of range or an unknown name (listing the names).
            TypeError: for anything else.
        """
        if isinstance(joint, str):
            found = self._by_name.get(joint)
            if found is None:
                raise ValueError(
                    f"{self.owner}: no joint named {joint!r}; known joints: {self.names}"
                )
            return found
        if isinstance(joint, (bool, np.bool_)) or not isinstance(joint, (int, np.integer)):
            raise TypeError(f"{self.owner}: joint must be an index or a name, got {joint!r}")
        if not 0 <= int(joint) < len(self.infos):
            raise ValueError(
                f"{self.owner}: joint index {joint} out of range [0, {len(self.infos)})"
            )
        return int(joint)

    # ----- checkpoints ----------------------------------------------------------------------

    def get_state(self) -> dict[str, Any]:
        """Positions, velocities, targets, forces and whether joints move (checkpoints)."""
        self.refresh()
        return {
            "positions": self.positions.copy(),
            "velocities": self.velocities.copy(),
            "targets": self.targets.copy(),
            "forces": self.forces.copy(),
            "moving": self.moving,
        }

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore :meth:`get_state` (kinematic joints; PyBullet's joints are reset to it).

        Raises:
            ValueError: for another number of joints.
        """
        if len(state["positions"]) != len(self.infos):
            raise ValueError(
                f"{self.owner}: the checkpoint has {len(state['positions'])} joints, this "
                f"body {len(self.infos)}"
            )
        self.set_positions(dict(enumerate(state["positions"].tolist())))
        self.velocities[:] = state["velocities"]
        self.targets[:] = state["targets"]
        self.forces[:] = state["forces"]
        self.moving = bool(state["moving"])

    # ----- reading -------------------------------------------------------------------------

    def refresh(self) -> None:
        """Re-read positions and velocities from PyBullet (physics joints only)."""
        if self.kinematic or not len(self.infos):
            return
        states = p.getJointStates(
            self.body_id, list(range(len(self.infos))), physicsClientId=self.client
        )
        self.positions[:] = [s[0] for s in states]
        self.velocities[:] = [s[1] for s in states]

    def state(self, j: int) -> tuple[float, float]:
        """(position, velocity) of joint ``j``."""
        self.refresh()
        return float(self.positions[j]), float(self.velocities[j])

    # ----- commanding ----------------------------------------------------------------------

    def set_target(self, j: int, target: float, max_force: float) -> None:
        """Command joint ``j`` to ``target`` (clamped to its limits, with a warning).

        Raises:
            ValueError: for a fixed joint, a non-finite target or a negative force.
        """
        info = self.infos[j]
        if not info.is_movable:
            raise ValueError(
                f"{self.owner}: joint {info.name!r} (index {j}) is fixed and cannot be moved"
            )
        if isinstance(target, bool) or not isinstance(target, (int, float, np.number)):
            raise ValueError(
                f"{self.owner}: target for joint {info.name!r} must be a number, got {target!r}"
            )
        value = float(target)
        if not math.isfinite(value):
            raise ValueError(f"{self.owner}: target for joint {info.name!r} is {value}")
        if not max_force >= 0:
            raise ValueError(f"{self.owner}: max_force must be >= 0 (N), got {max_force!r}")
        clamped = min(max(value, info.lower), info.upper)
        if clamped != value:
            logger.warning(
                "%s: target %.4g for joint %r is outside its limits [%.4g, %.4g]; using %.4g",
                self.owner,
                value,
                info.name,
                info.lower,
                info.upper,
                clamped,
            )
        self.targets[j] = clamped
        self.forces[j] = float(max_force)
        if not self.kinematic:
            p.setJointMotorControl2(
                self.body_id,
                j,
                p.POSITION_CONTROL,
                targetPosition=clamped,
                force=float(max_force),
                maxVelocity=info.max_velocity,
                physicsClientId=self.client,
            )
        self.moving = True

    def hold(self) -> None:
        """Stop every commanded joint where it is now (its target becomes its position)."""
        self.refresh()
        active = ~np.isnan(self.targets)
        self.targets[active] = self.positions[active]
        self.velocities[:] = 0.0
        if not self.kinematic:
            for j in np.flatnonzero(active):
                p.setJointMotorControl2(
                    self.body_id,
                    int(j),
                    p.POSITION_CONTROL,
                    targetPosition=float(self.positions[j]),
                    force=float(self.forces[j]),
                    physicsClientId=self.client,
                )
        self.moving = False

    def set_positions(self, values: Mapping[int, float]) -> None:
        """Teleport joints (kinematic reset): positions written, velocities zeroed."""
        for j, value in values.items():
            self.positions[j] = float(value)
            self.velocities[j] = 0.0
            p.resetJointState(self.body_id, j, float(value), physicsClientId=self.client)

    # ----- stepping ------------------------------------------------------------------------

    def advance(self, dt: float) -> bool:
        """Move kinematic joints one step towards their targets; return whether any moved.

        Each joint moves at most ``max_velocity * dt`` and lands exactly on its target.
        Physics joints are moved by PyBullet; this only re-reads them.
        """
        if not self.kinematic:
            self.refresh()
            active = ~np.isnan(self.targets)
            # Motors approach their targets asymptotically: settled within 0.1 mrad / mm.
            self.moving = bool(np.any(np.abs(self.positions[active] - self.targets[active]) > 1e-4))
            return True
        active = ~np.isnan(self.targets)
        delta = np.where(active, self.targets - self.positions, 0.0)
        step_max = self.max_velocity * dt
        step = np.clip(delta, -step_max, step_max)
        changed = np.flatnonzero(step != 0.0)
        self.velocities[:] = step / dt if dt > 0 else 0.0
        if not len(changed):
            self.moving = False
            return False
        self.positions[changed] += step[changed]
        arrived = np.abs(delta[changed]) <= step_max[changed]
        self.positions[changed[arrived]] = self.targets[changed[arrived]]
        p.resetJointStatesMultiDof(
            self.body_id,
            changed.tolist(),
            [[float(v)] for v in self.positions[changed]],
            physicsClientId=self.client,
        )
        self.moving = bool(np.any(self.positions[active] != self.targets[active]))
        return True

    # ----- tolerance -----------------------------------------------------------------------

    def tolerance_for(self, tolerance: Any, j: int, default: float) -> float:
        """Resolve a tolerance spec for joint ``j``.

        A float applies to every joint; a list is indexed by joint index; a dict is keyed by
        joint name, and joints it does not name use ``default``.

        Raises:
            ValueError: for a list too short for ``j``, or a negative / non-numeric value.
        """
        if isinstance(tolerance, Mapping):
            value = tolerance.get(self.infos[j].name, default)
        elif isinstance(tolerance, (list, tuple, np.ndarray)):
            if j >= len(tolerance):
                raise ValueError(
                    f"{self.owner}: tolerance list has {len(tolerance)} entries, "
                    f"none for joint index {j} ({self.infos[j].name!r})"
                )
            value = tolerance[j]
        else:
            value = tolerance
        if not _finite_tolerance(value):
            raise ValueError(
                f"{self.owner}: joint tolerance for {self.infos[j].name!r} must be a finite "
                f"number >= 0, got {short_repr(value)}"
            )
        return float(value)

    def within(self, targets: Mapping[int, float], tolerance: Any, default: float) -> bool:
        """Whether every joint in ``targets`` is within its tolerance of its target."""
        self.refresh()
        return all(
            abs(self.positions[j] - float(t)) <= self.tolerance_for(tolerance, j, default)
            for j, t in targets.items()
        )


class JointMotion(Generic[A]):
    """Advances the joints of every agent with moving joints, once per step.

    Args:
        wake: Called with each agent whose joints moved this step, so an action waiting on
            its joints can check whether they have arrived.
    """

    def __init__(self, wake: Callable[[A], None]) -> None:
        self._wake = wake
        self._active: dict[int, tuple[A, JointSet]] = {}

    def __len__(self) -> int:
        return len(self._active)

    def activate(self, agent: A, joints: JointSet) -> None:
        """Start advancing ``agent``'s joints each step (until they arrive)."""
        self._active[agent.object_id] = (agent, joints)

    def active_ids(self) -> list[int]:
        """Object ids of the agents whose joints are moving, ascending."""
        return sorted(self._active)

    def forget(self, agent: A) -> None:
        """Stop advancing ``agent`` (it left the simulation)."""
        self._active.pop(agent.object_id, None)

    def reset(self) -> None:
        """Forget every agent (simulation reset)."""
        self._active.clear()

    def advance(self, dt: float) -> None:
        """Move every active agent's joints one step, in ascending object id."""
        if not self._active:
            return
        for key in sorted(self._active):
            agent, joints = self._active[key]
            joints.advance(dt)
            if not joints.moving:
                del self._active[key]
                if joints.kinematic:
                    joints.velocities[:] = 0.0  # at rest from now on
            self._wake(agent)
