"""Pose: a position and unit-quaternion orientation, validated once at construction.

Quaternions are ``(x, y, z, w)`` like PyBullet; Euler angles follow
``pybullet.getQuaternionFromEuler``. Positions are in metres, angles in radians.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from fleet_async.core.geometry.quaternions import (
    Quat,
    euler_from_quat,
    quat_from_euler,
    quat_multiply,
    rotate_vector,
)

__all__ = ["Pose"]

_IDENTITY: Quat = (0.0, 0.0, 0.0, 1.0)
_IDENTITY_ARRAY = np.array(_IDENTITY)  # copied, never handed out
# A stored orientation's squared norm is within this of 1; anything further is normalised.
_UNIT_TOLERANCE = 1e-12


def _finite_floats(value: object, n: int, field: str, layout: str) -> list[float]:
    """Return ``value`` as ``n`` finite Python numbers, or raise ValueError naming ``field``."""
    arr = np.asarray(value)
    if arr.shape == (n,) and arr.dtype.kind in "iuf":
        values = arr.tolist()
        if all(map(math.isfinite, values)):
            return values
    raise ValueError(f"{field}: expected {n} finite numbers {layout}, got {value!r}")


def _unit_quat(value: object, field: str) -> np.ndarray:
    q = _finite_floats(value, 4, field, "[x, y, z, w]")
    x, y, z, w = q
    n2 = x * x + y * y + z * z + w * w
    if abs(n2 - 1.0) <= _UNIT_TOLERANCE:
        return np.array(q, dtype=np.float64)
    norm = math.hypot(*q)  # scales internally: tiny or huge components neither under- nor overflow
    if norm == 0.0:
        raise ValueError(f"{field}: zero-norm quaternion has no rotation, got {value!r}")
    return np.array([c / norm for c in q], dtype=np.float64)


class Pose:
    """Position and orientation of a frame; compatible with ROS 2 ``geometry_msgs/Pose``.

    Construction validates and copies its inputs and normalises the quaternion. Poses compare
    equal when both arrays are exactly equal; they are mutable and so unhashable.

    Attributes:
        position: ``[x, y, z]`` in metres in the parent (usually world) frame, float64 ``(3,)``.
        orientation: Unit quaternion ``[x, y, z, w]``, float64 ``(4,)``.
    """

    __slots__ = ("orientation", "position")

    position: np.ndarray
    orientation: np.ndarray

    def __init__(
        self,
        position: Sequence[float] | np.ndarray,
        orientation: Sequence[float] | np.ndarray = _IDENTITY,
    ) -> None:
        """Create a pose.

        Args:
            position: ``[x, y, z]`` in metres.
            orientation: Quaternion ``[x, y, z, w]``; normalised if not unit. Defaults to no
                rotation.

        Raises:
            ValueError: If ``position`` is not 3 finite numbers, ``orientation`` not 4 finite
                numbers, or ``orientation`` has zero norm; the message names the field.
        """
        self.position = np.array(
            _finite_floats(position, 3, "Pose.position", "[x, y, z]"), dtype=np.float64
        )
        if orientation is _IDENTITY:  # the default: skip validating a known-good constant
            self.orientation = _IDENTITY_ARRAY.copy()
        else:
            self.orientation = _unit_quat(orientation, "Pose.orientation")

    @classmethod
    def from_arrays_unchecked(cls, position: np.ndarray, orientation: np.ndarray) -> Pose:
        """Wrap arrays in a Pose with no validation and no copy (for internal hot paths).

        The caller guarantees ``position`` is a float64 ``(3,)`` array, ``orientation`` a
        float64 ``(4,)`` unit quaternion, and that neither is aliased elsewhere.
        """
        pose = cls.__new__(cls)
        pose.position = position
        pose.orientation = orientation
        return pose

    @classmethod
    def from_xyz(cls, x: float, y: float, z: float) -> Pose:
        """Create a pose at ``(x, y, z)`` metres with no rotation.

        Raises:
            ValueError: If a coordinate is not a finite number.
        """
        return cls((x, y, z))

    @classmethod
    def from_euler(
        cls, x: float, y: float, z: float, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0
    ) -> Pose:
        """Create a pose from a position in metres and roll/pitch/yaw in radians.

        Same convention as ``pybullet.getQuaternionFromEuler([roll, pitch, yaw])``: roll about
        X, then pitch about Y, then yaw about Z, all about the fixed parent axes.

        Raises:
            ValueError: If a coordinate or angle is not a finite number.
        """
        angles = _finite_floats((roll, pitch, yaw), 3, "Pose.from_euler", "[roll, pitch, yaw]")
        return cls((x, y, z), quat_from_euler(*angles))

    @classmethod
    def from_yaw(cls, x: float, y: float, z: float, yaw: float) -> Pose:
        """Create a pose from a position in metres and a yaw (about Z) in radians.

        Same as ``Pose.from_euler(x, y, z, yaw=yaw)``; the incumbent's scripts use this name.

        Raises:
            ValueError: If a coordinate or the angle is not a finite number.
        """
        return cls.from_euler(x, y, z, yaw=yaw)

    @classmethod
    def from_pybullet(
        cls, position: Sequence[float] | np.ndarray, orientation: Sequence[float] | np.ndarray
    ) -> Pose:
        """Create a pose from PyBullet's ``(position, orientation)`` pair.

        Raises:
            ValueError: As for ``Pose(position, orientation)``.
        """
        return cls(position, orientation)

    def as_position_orientation(self) -> tuple[list[float], list[float]]:
        """Return ``([x, y, z], [x, y, z, w])`` as Python floats, ready for PyBullet calls."""
        return self.position.tolist(), self.orientation.tolist()

    def as_tuple(self) -> tuple[list[float], list[float]]:
        """Alias of ``as_position_orientation``."""
        return self.as_position_orientation()

    def as_euler(self) -> tuple[float, float, float]:
        """Return the orientation as ``(roll, pitch, yaw)`` in radians (PyBullet convention).

        At gimbal lock (pitch = +-pi/2) roll is reported as 0 and the rest goes into yaw.
        """
        return euler_from_quat(self.orientation)

    @property
    def x(self) -> float:
        """X coordinate in metres."""
        return float(self.position[0])

    @property
    def y(self) -> float:
        """Y coordinate in metres."""
        return float(self.position[1])

    @property
    def z(self) -> float:
        """Z coordinate in metres."""
        return float(self.position[2])

    @property
    def roll(self) -> float:
        """Roll in radians (rotation about the X axis)."""
        return self.as_euler()[0]

    @property
    def pitch(self) -> float:
        """Pitch in radians (rotation about the Y axis)."""
        return self.as_euler()[1]

    @property
    def yaw(self) -> float:
        """Yaw in radians (rotation about the Z axis)."""
        return self.as_euler()[2]

    def compose(self, other: Pose) -> Pose:
        """Return ``self * other``: ``other`` is given in this pose's frame.

        Same as ``pybullet.multiplyTransforms(self..., other...)``.
        """
        offset = rotate_vector(other.position, self.orientation)
        quat = quat_multiply(self.orientation, other.orientation)
        return Pose.from_arrays_unchecked(self.position + offset, quat)

    def inverse(self) -> Pose:
        """Return the pose ``p`` with ``self.compose(p)`` the identity (parent seen from here)."""
        x, y, z, w = self.orientation.tolist()
        conj = np.array([-x, -y, -z, w])
        return Pose.from_arrays_unchecked(-rotate_vector(self.position, conj), conj)

    def distance_to(self, other: Pose) -> float:
        """Euclidean distance in metres between the two positions (orientation ignored)."""
        return math.dist(self.position.tolist(), other.position.tolist())

    def copy(self) -> Pose:
        """Return a deep copy (new arrays)."""
        return Pose.from_arrays_unchecked(self.position.copy(), self.orientation.copy())

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Pose):
            return NotImplemented
        return bool(
            np.array_equal(self.position, other.position)
            and np.array_equal(self.orientation, other.orientation)
        )

    __hash__ = None  # type: ignore[assignment]  # mutable, compared by value

    def __repr__(self) -> str:
        return f"Pose(position={self.position.tolist()}, orientation={self.orientation.tolist()})"
