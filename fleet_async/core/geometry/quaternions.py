"""Quaternion helpers in PyBullet's ``(x, y, z, w)`` convention: scalar, slerp and batched.

Scalar helpers use the ``math`` module on Python floats, which beats numpy for single
quaternions. The ``*_batch`` helpers take ``(N, 4)`` / ``(N, 3)`` arrays and never loop over
rows in Python; they are the simulator's per-step hot path.

All rotations are active: ``rotate_vector(v, q)`` expresses a vector given in a body frame
in the parent frame whose orientation is ``q``. ``quat_multiply(q1, q2)`` applies ``q2`` first.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

__all__ = [
    "Quat",
    "SlerpPrecomp",
    "compose_poses_batch",
    "euler_from_quat",
    "quat_angle_between",
    "quat_from_euler",
    "quat_from_rotvec",
    "quat_multiply",
    "quat_multiply_batch",
    "quat_slerp",
    "quat_slerp_batch",
    "quat_slerp_precompute",
    "quat_to_rot_matrix",
    "rotate_vector",
    "rotate_vectors_batch",
    "yaw_from_quats",
]

Quat = tuple[float, float, float, float]
"""Quaternion in ``(x, y, z, w)`` convention, the same as PyBullet."""

_QuatLike = Sequence[float] | np.ndarray

# Below this sin(theta_0), slerp weights lose precision; normalised lerp is then exact to
# well under 1e-12 because the two quaternions are within ~1e-6 rad of each other.
_SLERP_LINEAR_EPS = 1e-6
# Rotation vectors shorter than this use the Taylor series of sin(a/2)/a (error ~a^4/3840).
_ROTVEC_SMALL_ANGLE = 1e-6


def _floats(values: Sequence[float] | np.ndarray, n: int, name: str) -> list[float]:
    """Return ``values`` as a list of ``n`` Python floats, or raise ValueError naming ``name``."""
    seq = values.tolist() if isinstance(values, np.ndarray) else list(values)
    if len(seq) != n:
        raise ValueError(f"{name}: expected {n} numbers, got {values!r}")
    return [float(v) for v in seq]


def quat_to_rot_matrix(
    quat: _QuatLike,
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """Convert a quaternion to a 3x3 rotation matrix, flattened row-major.

    Args:
        quat: Quaternion ``(x, y, z, w)``; normalised here if not unit length.

    Returns:
        ``(r00, r01, r02, r10, r11, r12, r20, r21, r22)``; ``R @ v`` maps body-frame vectors
        into the parent frame.

    Raises:
        ValueError: If ``quat`` does not have 4 components or has zero norm.
    """
    x, y, z, w = _floats(quat, 4, "quat")
    n2 = x * x + y * y + z * z + w * w
    if n2 == 0.0:
        raise ValueError(f"quat: zero-norm quaternion {quat!r} has no rotation")
    s = 2.0 / n2  # dividing by n2 is what normalises a non-unit quaternion
    xx, yy, zz = x * x * s, y * y * s, z * z * s
    xy, xz, yz = x * y * s, x * z * s, y * z * s
    wx, wy, wz = w * x * s, w * y * s, w * z * s
    return (
        1.0 - yy - zz, xy - wz, xz + wy,
        xy + wz, 1.0 - xx - zz, yz - wx,
        xz - wy, yz + wx, 1.0 - xx - yy,
    )  # fmt: skip


def rotate_vector(vec: Sequence[float] | np.ndarray, quat: _QuatLike) -> np.ndarray:
    """Rotate a 3-D vector by a quaternion (same as SciPy's ``Rotation.from_quat(q).apply(v)``).

    Args:
        vec: Vector ``(x, y, z)`` in the rotated (body) frame.
        quat: Orientation ``(x, y, z, w)`` of that frame; normalised here.

    Returns:
        The vector expressed in the parent frame, shape ``(3,)``.

    Raises:
        ValueError: If the shapes are wrong or ``quat`` has zero norm.
    """
    vx, vy, vz = _floats(vec, 3, "vec")
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_to_rot_matrix(quat)
    return np.array(
        [
            r00 * vx + r01 * vy + r02 * vz,
            r10 * vx + r11 * vy + r12 * vz,
            r20 * vx + r21 * vy + r22 * vz,
        ]
    )


def quat_from_rotvec(rotvec: Sequence[float] | np.ndarray) -> np.ndarray:
    """Convert a rotation vector (unit axis times angle in radians) to a quaternion.

    Same as SciPy's ``Rotation.from_rotvec(rotvec).as_quat()``.

    Args:
        rotvec: Rotation vector ``(x, y, z)``; its norm is the angle in radians.

    Returns:
        Unit quaternion ``(x, y, z, w)``, shape ``(4,)``.

    Raises:
        ValueError: If ``rotvec`` does not have 3 components.
    """
    x, y, z = _floats(rotvec, 3, "rotvec")
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < _ROTVEC_SMALL_ANGLE:
        scale = 0.5 - angle * angle / 48.0
    else:
        scale = math.sin(0.5 * angle) / angle
    return np.array([x * scale, y * scale, z * scale, math.cos(0.5 * angle)])


def _mul(a: Sequence[float], b: Sequence[float]) -> list[float]:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]


def quat_from_euler(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Quaternion for roll, pitch, yaw in radians; same as ``pybullet.getQuaternionFromEuler``.

    Roll about X, then pitch about Y, then yaw about Z, all about the fixed parent axes
    (``q = q_yaw * q_pitch * q_roll``).

    Returns:
        Unit quaternion ``(x, y, z, w)``, shape ``(4,)``.
    """
    cr, sr = math.cos(0.5 * roll), math.sin(0.5 * roll)
    cp, sp = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    cy, sy = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    return np.array(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ]
    )


def euler_from_quat(quat: _QuatLike) -> tuple[float, float, float]:
    """Roll, pitch, yaw in radians of a unit quaternion (``quat_from_euler``'s inverse).

    Roll and yaw are in ``[-pi, pi]``, pitch in ``[-pi/2, pi/2]``. At gimbal lock
    (pitch = +-pi/2) only one of roll and yaw is determined: roll is reported as 0.

    Raises:
        ValueError: If ``quat`` does not have 4 components.
    """
    x, y, z, w = _floats(quat, 4, "quat")
    sin_pitch = 2.0 * (w * y - x * z)
    if abs(sin_pitch) >= 1.0 - 1e-12:
        yaw = math.remainder(2.0 * math.atan2(z, w), 2.0 * math.pi)
        return 0.0, math.copysign(0.5 * math.pi, sin_pitch), yaw
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, math.asin(sin_pitch), yaw


def quat_multiply(q1: _QuatLike, q2: _QuatLike) -> np.ndarray:
    """Hamilton product ``q1 * q2``: the rotation that applies ``q2`` first, then ``q1``.

    Args:
        q1: Left quaternion ``(x, y, z, w)``.
        q2: Right quaternion ``(x, y, z, w)``.

    Returns:
        The product, shape ``(4,)``; unit if both inputs are unit.

    Raises:
        ValueError: If either input does not have 4 components.
    """
    return np.array(_mul(_floats(q1, 4, "q1"), _floats(q2, 4, "q2")))


def quat_angle_between(q0: _QuatLike, q1: _QuatLike) -> float:
    """Angle in radians, in ``[0, pi]``, of the rotation taking ``q0`` to ``q1``.

    ``q`` and ``-q`` are the same rotation, and non-unit inputs are accepted: the angle is
    ``2 * atan2(|v|, |w|)`` of ``q1 * conj(q0)``, which is scale invariant and keeps full
    precision for tiny angles (unlike ``acos`` of a dot product).

    Args:
        q0: Start orientation ``(x, y, z, w)``.
        q1: End orientation ``(x, y, z, w)``.

    Returns:
        The rotation angle in radians.

    Raises:
        ValueError: If an input does not have 4 components or has zero norm.
    """
    a = _floats(q0, 4, "q0")
    b = _floats(q1, 4, "q1")
    for name, q, raw in (("q0", a, q0), ("q1", b, q1)):
        if not any(q):
            raise ValueError(f"{name}: zero-norm quaternion {raw!r} has no rotation")
    x, y, z, w = _mul(b, [-a[0], -a[1], -a[2], a[3]])
    return 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w))


class SlerpPrecomp(NamedTuple):
    """Constants for slerp between two fixed unit quaternions (see ``quat_slerp_precompute``).

    Attributes:
        dot: ``|dot(q0, q1)|``, clamped to ``[0, 1]``.
        theta_0: Half the rotation angle between the keyframes, ``acos(dot)``, in radians.
        sin_theta_0: ``sin(theta_0)``.
        needs_flip: True if ``dot(q0, q1) < 0``, so ``-q1`` is the shortest-path target.
    """

    dot: float
    theta_0: float
    sin_theta_0: float
    needs_flip: bool


def quat_slerp_precompute(q0: _QuatLike, q1: _QuatLike) -> SlerpPrecomp:
    """Precompute the constants for slerping from ``q0`` to ``q1`` along the shortest path.

    Args:
        q0: Start unit quaternion ``(x, y, z, w)``.
        q1: End unit quaternion ``(x, y, z, w)``.

    Returns:
        The constants ``quat_slerp`` needs.

    Raises:
        ValueError: If an input does not have 4 components.
    """
    a = _floats(q0, 4, "q0")
    b = _floats(q1, 4, "q1")
    dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
    needs_flip = dot < 0.0
    dot = min(abs(dot), 1.0)
    theta_0 = math.acos(dot)
    return SlerpPrecomp(dot, theta_0, math.sin(theta_0), needs_flip)


def quat_slerp(q0: _QuatLike, q1: _QuatLike, t: float, precomp: SlerpPrecomp) -> np.ndarray:
    """Spherical linear interpolation between two fixed unit quaternions.

    Meant for the two-keyframe case: compute ``precomp`` once, then call this per step with
    a new ``t``. When the keyframes (nearly) coincide it falls back to normalised lerp.

    Args:
        q0: Start unit quaternion ``(x, y, z, w)``.
        q1: End unit quaternion ``(x, y, z, w)``; not sign-corrected (``precomp`` says).
        t: Interpolation parameter; 0 gives ``q0``, 1 gives ``q1`` (or ``-q1``).
        precomp: ``quat_slerp_precompute(q0, q1)``.

    Returns:
        Unit quaternion ``(x, y, z, w)``, shape ``(4,)``.
    """
    a = _floats(q0, 4, "q0")
    b = _floats(q1, 4, "q1")
    sign = -1.0 if precomp.needs_flip else 1.0
    if precomp.sin_theta_0 < _SLERP_LINEAR_EPS:
        out = [(1.0 - t) * ai + t * sign * bi for ai, bi in zip(a, b, strict=True)]
        norm = math.sqrt(sum(v * v for v in out))
        return np.array([v / norm for v in out])
    s0 = math.sin((1.0 - t) * precomp.theta_0) / precomp.sin_theta_0
    s1 = sign * math.sin(t * precomp.theta_0) / precomp.sin_theta_0
    return np.array([s0 * ai + s1 * bi for ai, bi in zip(a, b, strict=True)])


def quat_slerp_batch(
    q0: np.ndarray,
    q1: np.ndarray,
    t: np.ndarray,
    dot: np.ndarray,
    theta0: np.ndarray,
    sin_theta0: np.ndarray,
) -> np.ndarray:
    """Vectorised slerp for N quaternion pairs.

    The caller does the shortest-path correction: ``q1`` rows are already negated where
    ``dot(q0, q1) < 0`` and ``dot`` is the corrected, non-negative value. Rows whose
    ``sin_theta0`` is near zero use normalised lerp, without division warnings.

    Args:
        q0: ``(N, 4)`` start unit quaternions.
        q1: ``(N, 4)`` end unit quaternions, sign-corrected.
        t: ``(N,)`` interpolation parameters in ``[0, 1]``.
        dot: ``(N,)`` corrected dot products, ``>= 0``.
        theta0: ``(N,)`` half-angles ``acos(dot)`` in radians.
        sin_theta0: ``(N,)`` values ``sin(theta0)``.

    Returns:
        ``(N, 4)`` interpolated unit quaternions.
    """
    del dot  # part of the reference signature; theta0 and sin_theta0 carry what is needed
    linear = sin_theta0 < _SLERP_LINEAR_EPS
    safe_sin = np.where(linear, 1.0, sin_theta0)
    s0 = np.where(linear, 1.0 - t, np.sin((1.0 - t) * theta0) / safe_sin)
    s1 = np.where(linear, t, np.sin(t * theta0) / safe_sin)
    out = s0[:, None] * q0 + s1[:, None] * q1
    if linear.any():
        norms = np.where(linear, np.linalg.norm(out, axis=1), 1.0)
        out /= norms[:, None]
    return out


def _as_rows(values: np.ndarray | Sequence[Sequence[float]], width: int, name: str) -> np.ndarray:
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != width:
        raise ValueError(f"{name}: expected an (N, {width}) array, got shape {arr.shape}")
    return arr


def quat_multiply_batch(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Row-wise Hamilton product ``q1[i] * q2[i]`` (apply ``q2[i]`` first, then ``q1[i]``).

    Args:
        q1: ``(N, 4)`` left quaternions ``(x, y, z, w)``.
        q2: ``(N, 4)`` right quaternions ``(x, y, z, w)``.

    Returns:
        ``(N, 4)`` products.

    Raises:
        ValueError: If either input is not ``(N, 4)`` or the row counts differ.
    """
    a = _as_rows(q1, 4, "q1")
    b = _as_rows(q2, 4, "q2")
    if a.shape != b.shape:
        raise ValueError(f"q1 and q2: row counts differ, got {a.shape} and {b.shape}")
    ax, ay, az, aw = a.T
    bx, by, bz, bw = b.T
    out = np.empty_like(a)
    out[:, 0] = aw * bx + ax * bw + ay * bz - az * by
    out[:, 1] = aw * by - ax * bz + ay * bw + az * bx
    out[:, 2] = aw * bz + ax * by - ay * bx + az * bw
    out[:, 3] = aw * bw - ax * bx - ay * by - az * bz
    return out


def rotate_vectors_batch(vecs: np.ndarray, quats: np.ndarray) -> np.ndarray:
    """Rotate each ``vecs[i]`` by ``quats[i]`` (row-wise ``rotate_vector``).

    Quaternions need not be unit: ``v' = ((w^2 - u.u) v + 2 (u.v) u + 2 w (u x v)) / |q|^2``
    is scale invariant.

    Args:
        vecs: ``(N, 3)`` vectors in the body frames.
        quats: ``(N, 4)`` body orientations ``(x, y, z, w)``.

    Returns:
        ``(N, 3)`` vectors in the parent frame.

    Raises:
        ValueError: If the shapes are wrong, the row counts differ, or a quaternion is zero.
    """
    v = _as_rows(vecs, 3, "vecs")
    q = _as_rows(quats, 4, "quats")
    if v.shape[0] != q.shape[0]:
        raise ValueError(f"vecs and quats: row counts differ, got {v.shape} and {q.shape}")
    u = q[:, :3]
    w = q[:, 3:]
    uu = np.einsum("ij,ij->i", u, u)[:, None]
    n2 = uu + w * w
    if not n2.all():
        bad = int(np.flatnonzero(n2[:, 0] == 0.0)[0])
        raise ValueError(f"quats[{bad}]: zero-norm quaternion {q[bad].tolist()!r}")
    uv = np.einsum("ij,ij->i", u, v)[:, None]
    return ((w * w - uu) * v + 2.0 * uv * u + 2.0 * w * _cross(u, v)) / n2


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise ``np.cross`` of (N, 3) arrays: the same products and differences, so the same
    bits, without its axis handling (which cost more than the arithmetic on a few rows)."""
    out = np.empty(a.shape)
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    out[:, 0] = a1 * b2 - a2 * b1
    out[:, 1] = a2 * b0 - a0 * b2
    out[:, 2] = a0 * b1 - a1 * b0
    return out


def compose_poses_batch(
    parent_pos: np.ndarray,
    parent_quat: np.ndarray,
    rel_pos: np.ndarray,
    rel_quat: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Compose parent poses with relative poses row-wise: ``parent[i] * rel[i]``.

    Row by row this is ``pybullet.multiplyTransforms(parent_pos, parent_quat, rel_pos,
    rel_quat)`` in double precision: ``rel`` is given in the parent's frame, the result in the
    frame the parent is given in (e.g. world). The quaternion is the raw Hamilton product;
    PyBullet may return its negation, which is the same rotation.

    Args:
        parent_pos: ``(N, 3)`` parent positions in metres.
        parent_quat: ``(N, 4)`` parent orientations ``(x, y, z, w)``.
        rel_pos: ``(N, 3)`` positions relative to the parents, in metres.
        rel_quat: ``(N, 4)`` orientations relative to the parents.

    Returns:
        ``(positions (N, 3), orientations (N, 4))`` of the composed poses.

    Raises:
        ValueError: If a shape is wrong or the row counts differ.
    """
    pos = _as_rows(parent_pos, 3, "parent_pos")
    offset = rotate_vectors_batch(rel_pos, parent_quat)
    if pos.shape != offset.shape:
        raise ValueError(
            f"parent_pos and rel_pos: row counts differ, got {pos.shape} and {offset.shape}"
        )
    return pos + offset, quat_multiply_batch(parent_quat, rel_quat)


def yaw_from_quats(quats: np.ndarray) -> np.ndarray:
    """Yaw (rotation about world Z, radians in ``[-pi, pi]``) of each quaternion.

    Same convention as the third angle of ``pybullet.getEulerFromQuaternion``; scale
    invariant, so non-unit quaternions are accepted.

    Args:
        quats: ``(N, 4)`` orientations ``(x, y, z, w)``.

    Returns:
        ``(N,)`` yaw angles in radians.

    Raises:
        ValueError: If ``quats`` is not ``(N, 4)``.
    """
    x, y, z, w = _as_rows(quats, 4, "quats").T
    return np.arctan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z)
