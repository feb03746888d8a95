"""Shape parameters and PyBullet shape creation with a shared per-client cache.

Identical shape parameters map to one PyBullet shape id, so spawning ten thousand boxes creates
one collision shape and one visual shape, not ten thousand of each. The cache is keyed by
physics client and cleared when that client's world is reset (shape ids die with the world).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any

import pybullet as p

from fleet_async.core.base.config_utils import dataclass_from_dict
from fleet_async.core.base.paths import resolve_data_file
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.pose_config import pose_from_config

__all__ = [
    "SHAPE_TYPES",
    "ShapeParams",
    "body_collision_shape",
    "clear_shape_cache",
    "forget_body_shape",
    "get_or_create_shapes",
    "record_body_shape",
]

SHAPE_TYPES = ("box", "sphere", "cylinder", "mesh")


def _finite_list(value: Any, n: int) -> bool:
    try:
        items = list(value)
    except TypeError:
        return False
    return len(items) == n and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in items
    )


@dataclass
class ShapeParams:
    """Visual or collision geometry, like a URDF ``<visual>`` / ``<collision>`` element.

    Attributes:
        shape_type: "box", "sphere", "cylinder", "mesh", or None for no shape.
        mesh_path: Mesh file (OBJ/STL); required for "mesh". Relative paths are searched in the
            working directory, the simulation's ``model_paths`` and pybullet_data.
        mesh_scale: [sx, sy, sz] scale of a mesh.
        half_extents: [hx, hy, hz] of a box, metres.
        radius: Sphere / cylinder radius, metres.
        height: Cylinder height, metres.
        rgba_color: [r, g, b, a] in 0..1 (visual shapes only).
        frame_pose: Offset of the shape in the body frame.
    """

    shape_type: str | None = None
    mesh_path: str | None = None
    mesh_scale: list[float] = field(default_factory=lambda: [1.0, 1.0, 1.0])
    half_extents: list[float] = field(default_factory=lambda: [0.5, 0.5, 0.5])
    radius: float = 0.5
    height: float = 1.0
    rgba_color: list[float] = field(default_factory=lambda: [0.8, 0.8, 0.8, 1.0])
    frame_pose: Pose | None = None

    def __post_init__(self) -> None:
        def bad(name: str, expected: str) -> ValueError:
            return ValueError(
                f"ShapeParams.{name}: expected {expected}, got {getattr(self, name)!r}"
            )

        if self.shape_type is not None:
            if not isinstance(self.shape_type, str) or self.shape_type.lower() not in SHAPE_TYPES:
                raise bad("shape_type", f"one of {SHAPE_TYPES} or None")
            self.shape_type = self.shape_type.lower()
        if self.shape_type == "mesh" and not self.mesh_path:
            raise ValueError("ShapeParams.mesh_path: required when shape_type is 'mesh', got None")
        if self.mesh_path is not None:
            self.mesh_path = os.fspath(self.mesh_path)
        for name, n in (("mesh_scale", 3), ("half_extents", 3), ("rgba_color", 4)):
            if not _finite_list(getattr(self, name), n):
                raise bad(name, f"{n} finite numbers")
            setattr(self, name, [float(v) for v in getattr(self, name)])
        if min(self.half_extents) <= 0:
            raise bad("half_extents", "3 numbers > 0")
        for name in ("radius", "height"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not value > 0:
                raise bad(name, "a number > 0")
        if not all(0.0 <= c <= 1.0 for c in self.rgba_color):
            raise bad("rgba_color", "4 numbers in [0, 1]")
        if self.frame_pose is not None and not isinstance(self.frame_pose, Pose):
            self.frame_pose = pose_from_config(self.frame_pose, field_name="ShapeParams.frame_pose")

    @classmethod
    def from_dict(cls, d: dict[str, Any], *, source: str | None = None) -> ShapeParams:
        """Build from a config mapping; unknown keys raise ValueError naming the key."""
        return dataclass_from_dict(cls, d, source=source, section="shape")

    def cache_key(self, visual: bool) -> tuple[Any, ...]:
        """Hashable identity of the PyBullet shape this describes."""
        frame = (
            ()
            if self.frame_pose is None
            else (
                tuple(self.frame_pose.position.tolist()),
                tuple(self.frame_pose.orientation.tolist()),
            )
        )
        color = tuple(self.rgba_color) if visual else ()
        return (
            self.shape_type,
            self.mesh_path,
            tuple(self.mesh_scale),
            tuple(self.half_extents),
            self.radius,
            self.height,
            color,
            frame,
        )


# (client id, visual?, cache key) -> PyBullet shape id
_SHAPE_CACHE: dict[tuple[int, bool, tuple[Any, ...]], int] = {}


# (client id, body id) -> the single collision shape a body was built from. The collision
# system queries PyBullet with (shape, pose from the state store) for these bodies, so their
# poses never need to be pushed to PyBullet just for a distance query.
_BODY_SHAPES: dict[tuple[int, int], int] = {}


def record_body_shape(client: int, body: int, collision_shape: int) -> None:
    """Remember that ``body`` is exactly ``collision_shape`` at its base pose."""
    if collision_shape >= 0:
        _BODY_SHAPES[(client, body)] = collision_shape


def body_collision_shape(client: int, body: int) -> int:
    """The single collision shape ``body`` was built from, or -1 if unknown / compound."""
    return _BODY_SHAPES.get((client, body), -1)


def forget_body_shape(client: int, body: int) -> None:
    """Drop the record of a removed body."""
    _BODY_SHAPES.pop((client, body), None)


def clear_shape_cache(client: int | None = None) -> None:
    """Forget cached shape ids of one client (after its world reset), or of all clients."""
    if client is None:
        _SHAPE_CACHE.clear()
        _BODY_SHAPES.clear()
        return
    for key in [k for k in _SHAPE_CACHE if k[0] == client]:
        del _SHAPE_CACHE[key]
    for body_key in [k for k in _BODY_SHAPES if k[0] == client]:
        del _BODY_SHAPES[body_key]


def _create_shape(
    shape: ShapeParams, visual: bool, client: int, search_paths: list[str] | None
) -> int:
    frame = shape.frame_pose or Pose([0.0, 0.0, 0.0])
    pos, orn = frame.as_position_orientation()
    geom = {
        "box": p.GEOM_BOX,
        "sphere": p.GEOM_SPHERE,
        "cylinder": p.GEOM_CYLINDER,
        "mesh": p.GEOM_MESH,
    }
    kwargs: dict[str, Any] = {"shapeType": geom[str(shape.shape_type)], "physicsClientId": client}
    if shape.shape_type == "box":
        kwargs["halfExtents"] = shape.half_extents
    elif shape.shape_type == "sphere":
        kwargs["radius"] = shape.radius
    elif shape.shape_type == "cylinder":
        kwargs["radius"] = shape.radius
        kwargs["length" if visual else "height"] = shape.height
    else:
        kwargs["fileName"] = resolve_data_file(str(shape.mesh_path), search_paths, "mesh_path")
        kwargs["meshScale"] = shape.mesh_scale
    if visual:
        kwargs.update(
            rgbaColor=shape.rgba_color, visualFramePosition=pos, visualFrameOrientation=orn
        )
        shape_id = p.createVisualShape(**kwargs)
    else:
        kwargs.update(collisionFramePosition=pos, collisionFrameOrientation=orn)
        shape_id = p.createCollisionShape(**kwargs)
    if shape_id < 0:
        kind = "visual" if visual else "collision"
        raise ValueError(f"PyBullet could not create the {kind} shape {shape!r}")
    return int(shape_id)


def get_or_create_shapes(
    visual_shape: ShapeParams | None,
    collision_shape: ShapeParams | None,
    client: int,
    search_paths: list[str] | None = None,
) -> tuple[int, int]:
    """Return (visual_id, collision_id) for the shapes, creating each at most once per client.

    A missing shape (None or ``shape_type=None``) yields -1, PyBullet's "no shape".
    """
    ids = []
    for shape, visual in ((visual_shape, True), (collision_shape, False)):
        if shape is None or shape.shape_type is None:
            ids.append(-1)
            continue
        key = (client, visual, shape.cache_key(visual))
        shape_id = _SHAPE_CACHE.get(key)
        if shape_id is None:
            shape_id = _create_shape(shape, visual, client, search_paths)
            _SHAPE_CACHE[key] = shape_id
        ids.append(shape_id)
    return ids[0], ids[1]
