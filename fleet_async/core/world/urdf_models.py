"""URDF models read once per simulation, so a fleet of one URDF is parsed once.

``loadURDF`` parses the file, loads its meshes and builds its shapes on every call (about 2 ms
for the project's mobile manipulator, 23 ms for ``pybullet_data``'s husky, whose visual meshes
are read again each time), and its cost grows with the bodies in the world. A kinematic
simulation needs none of that to spawn the next robot of a model it already holds: the first
robot of each model is loaded for real, what the simulation needs of the model is read back
from that body once (:class:`UrdfModel`: its base's inertial frame, its total mass, its
bounding box in the base frame), and every later robot of the model gets its row at once and a
*pending* body (``world/pending.py``), loaded with ``loadURDF`` only when something needs
PyBullet's view of it. Those bodies are what ``loadURDF`` makes, so everything read from them
(joints, links, limits, colours, contacts) is what it always was.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pybullet as p

from fleet_async.core.world.link_colours import one_colour_per_link

__all__ = ["UrdfKey", "UrdfModel", "load_urdf_body", "read_urdf_model"]


@dataclass(frozen=True)
class UrdfKey:
    """What makes two URDF bodies the same: the file (absolute path), a fixed base, and
    every link made massless (``mass=0.0`` at spawn)."""

    path: str
    use_fixed_base: bool
    zero_mass: bool


@dataclass(frozen=True)
class UrdfModel:
    """What a simulation keeps of a URDF model after loading it once.

    Attributes:
        key: The model.
        inertial_position, inertial_orientation: The base's inertial frame in its URDF link
            frame (PyBullet's base pose is that frame's pose).
        total_mass: kg, every link summed (as ``body_total_mass`` reads it).
        center, half: The union of its links' AABBs, as PyBullet reports them with the base at
            identity orientation, joints at rest: centre offset from the base position and
            half extents (m).
    """

    key: UrdfKey
    inertial_position: tuple[float, ...]
    inertial_orientation: tuple[float, ...]
    total_mass: float
    center: np.ndarray
    half: np.ndarray

    def base_pose(
        self, position: Sequence[float], orientation: Sequence[float]
    ) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """The base pose PyBullet reports for a body ``loadURDF`` puts at this URDF link-frame
        pose: the same float operations, so the same numbers (see :func:`_bullet_matrix`)."""
        rot, quat = _base_rotation(tuple(float(v) for v in orientation), self.inertial_orientation)
        ip = self.inertial_position
        pos = tuple(
            float(position[i]) + (rot[i][0] * ip[0] + rot[i][1] * ip[1] + rot[i][2] * ip[2])
            for i in range(3)
        )
        return pos, quat


@functools.lru_cache(maxsize=1024)  # a fleet is mostly spawned at a few orientations
def _base_rotation(
    orientation: tuple[float, ...], inertial: tuple[float, ...]
) -> tuple[list[list[float]], tuple[float, float, float, float]]:
    """The link frame's rotation matrix and the base quaternion PyBullet reports."""
    rot = _bullet_matrix(orientation)
    base = rot
    if inertial != (0.0, 0.0, 0.0, 1.0):
        frame = _bullet_matrix(inertial)
        base = [
            [_dot(rot[i], (frame[0][j], frame[1][j], frame[2][j])) for j in range(3)]
            for i in range(3)
        ]
    # PyBullet turns the matrix into its base quaternion and, when asked for the pose,
    # that quaternion into a matrix and back again.
    return rot, _bullet_quaternion(_bullet_matrix(_bullet_quaternion(base)))


def _dot(row: Sequence[float], col: Sequence[float]) -> float:
    """Bullet's 3-vector dot product, in its order."""
    return row[0] * col[0] + row[1] * col[1] + row[2] * col[2]


def _bullet_matrix(q: Sequence[float]) -> list[list[float]]:
    """Bullet's rotation matrix of quaternion ``q`` (x, y, z, w), operation for operation
    (``btMatrix3x3::setRotation``), so the last bits match PyBullet's."""
    x, y, z, w = (float(v) for v in q)
    s = 2.0 / (x * x + y * y + z * z + w * w)
    xs, ys, zs = x * s, y * s, z * s
    wx, wy, wz = w * xs, w * ys, w * zs
    xx, xy, xz = x * xs, x * ys, x * zs
    yy, yz, zz = y * ys, y * zs, z * zs
    return [
        [1.0 - (yy + zz), xy - wz, xz + wy],
        [xy + wz, 1.0 - (xx + zz), yz - wx],
        [xz - wy, yz + wx, 1.0 - (xx + yy)],
    ]


def _bullet_quaternion(m: list[list[float]]) -> tuple[float, float, float, float]:
    """Bullet's quaternion (x, y, z, w) of rotation matrix ``m`` (``btMatrix3x3::getRotation``,
    operation for operation)."""
    out = [0.0, 0.0, 0.0, 0.0]
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0.0:
        s = math.sqrt(trace + 1.0)
        out[3] = s * 0.5
        s = 0.5 / s
        out[0] = (m[2][1] - m[1][2]) * s
        out[1] = (m[0][2] - m[2][0]) * s
        out[2] = (m[1][0] - m[0][1]) * s
    else:
        big = (1, 2) if m[0][0] < m[1][1] else (0, 2)  # the largest diagonal entry
        i = big[1] if m[big[0]][big[0]] < m[2][2] else big[0]
        j, k = (i + 1) % 3, (i + 2) % 3
        s = math.sqrt(m[i][i] - m[j][j] - m[k][k] + 1.0)
        out[i] = s * 0.5
        s = 0.5 / s
        out[3] = (m[k][j] - m[j][k]) * s
        out[j] = (m[j][i] + m[i][j]) * s
        out[k] = (m[k][i] + m[i][k]) * s
    return out[0], out[1], out[2], out[3]


def load_urdf_body(
    key: UrdfKey, position: Sequence[float], orientation: Sequence[float], client: int
) -> int:
    """Load one body of ``key`` with ``loadURDF`` at a URDF link-frame pose: one colour per
    link, every link massless for ``key.zero_mass``.

    Raises:
        ValueError: when PyBullet cannot load the file (naming it).
    """
    try:
        # Cached graphics shapes: loading one model many times re-uses its visual
        # shapes instead of parsing them again (half the cost of each load).
        body = p.loadURDF(
            key.path,
            list(position),
            list(orientation),
            useFixedBase=key.use_fixed_base,
            flags=p.URDF_ENABLE_CACHED_GRAPHICS_SHAPES,
            physicsClientId=client,
        )
    except p.error as exc:
        raise ValueError(f"urdf_path {key.path!r}: PyBullet could not load it ({exc})") from exc
    one_colour_per_link(client, body, key.path)  # the GUI and recordings show it alike
    if key.zero_mass:
        for link in range(-1, p.getNumJoints(body, physicsClientId=client)):
            p.changeDynamics(body, link, mass=0.0, physicsClientId=client)
    return int(body)


def read_urdf_model(key: UrdfKey, body: int, client: int) -> UrdfModel:
    """Read a freshly loaded body of ``key`` (joints at rest) into a :class:`UrdfModel`.

    The body is turned to identity orientation to measure its AABB and put back exactly.
    """
    links = range(-1, p.getNumJoints(body, physicsClientId=client))
    base = p.getDynamicsInfo(body, -1, physicsClientId=client)
    total = float(sum(p.getDynamicsInfo(body, i, physicsClientId=client)[0] for i in links))
    pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=client)
    p.resetBasePositionAndOrientation(body, pos, [0, 0, 0, 1], physicsClientId=client)
    boxes = [p.getAABB(body, link, physicsClientId=client) for link in links]
    p.resetBasePositionAndOrientation(body, pos, orn, physicsClientId=client)
    lo = np.min([b[0] for b in boxes], axis=0)
    hi = np.max([b[1] for b in boxes], axis=0)
    return UrdfModel(
        key=key,
        inertial_position=tuple(base[3]),
        inertial_orientation=tuple(base[4]),
        total_mass=total,
        center=(lo + hi) / 2 - np.asarray(pos, dtype=float),
        half=(hi - lo) / 2,
    )
