"""Top-down footprints of bodies for traces: what the viewer draws for each body.

A footprint is the body-frame bounding box of every visual primitive of every link, seen from
above (a circle for a lone sphere or upright cylinder), with its height range and the colour
of the primitive that covers the most floor. Read from PyBullet's visual shape data once per
body when the body enters a trace; identical single-link bodies share one measurement. A body
still pending (``world/pending.py``) is described by its visual shape (a URDF robot by its
model): the first of each is created alone to be measured, the others stay pending.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
import pybullet as p

from fleet_async.core.world.pending import PENDING_BODY

if TYPE_CHECKING:
    from fleet_async.core.world.world import World

__all__ = ["describe_body"]

_GEOM_SPHERE, _GEOM_BOX, _GEOM_CYLINDER, _GEOM_MESH, _GEOM_CAPSULE = 2, 3, 4, 5, 7
_MARKER = {
    "type": "circle",
    "center": [0.0, 0.0],
    "radius": 0.05,
    "z": [-0.05, 0.05],
    "rgba": [0.5, 0.5, 0.5, 1.0],
}


def _yaw(q: Any) -> float:
    x, y, z, w = (float(v) for v in q)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _half_extents(body: int, link: int, geom: int, dims: Any, client: int) -> np.ndarray | None:
    """Half extents of one visual primitive in its own frame (None: not drawn from above)."""
    if geom == _GEOM_BOX:
        return np.asarray(dims[:3], dtype=float) / 2.0
    if geom == _GEOM_SPHERE:
        return np.full(3, float(dims[0]))
    if geom in (_GEOM_CYLINDER, _GEOM_CAPSULE):
        length, radius = float(dims[0]), float(dims[1])
        return np.array([radius, radius, length / 2.0 + (radius if geom == _GEOM_CAPSULE else 0)])
    if geom == _GEOM_MESH:  # the mesh's extent is not in the visual data: use the link's AABB
        lo, hi = p.getAABB(body, link, physicsClientId=client)
        return (np.asarray(hi) - np.asarray(lo)) / 2.0
    return None  # planes and heightfields


def _part_frame(
    body: int, link: int, local_pos: Any, local_orn: Any, client: int, base_inv: Any
) -> tuple[Any, Any]:
    """Pose of a visual primitive in the body (base inertial) frame."""
    if link < 0 or base_inv is None:
        return local_pos, local_orn
    state = p.getLinkState(body, link, computeForwardKinematics=1, physicsClientId=client)
    rel_pos, rel_orn = p.multiplyTransforms(base_inv[0], base_inv[1], state[0], state[1])
    return p.multiplyTransforms(rel_pos, rel_orn, local_pos, local_orn)


def describe_body(
    obj: Any, world: World, cache: dict[tuple[Any, ...], dict[str, Any]]
) -> tuple[dict[str, Any], list[float]]:
    """Top-down footprint of ``obj`` in its body frame, and its pose ``[x, y, z, yaw]``.

    The footprint is the body-frame bounding box of every visual primitive of every link (a
    circle for a lone sphere or upright cylinder), coloured like the primitive that covers
    the most floor; ``z`` is the body-frame height range, for the viewer's height filter.
    ``cache`` holds the footprints of single-link bodies by their visual data (and of pending
    bodies by their visual shape), so a fleet of identical robots is measured once. The pose
    comes from the state store; no body is created but the first pending one of a shape.
    """
    pose = obj.get_pose()
    where = [*(float(v) for v in pose.position), _yaw(pose.orientation)]
    body = obj.raw_body_id  # not obj.body_id: that would create every pending body
    client = world.client
    pending_key: tuple[Any, ...] | None = None
    if body == PENDING_BODY:
        group = world.pending_group(obj.state_row)
        # Shape bodies by their visual shape; URDF robots (joints at rest until their body
        # exists) by their model.
        pending_key = ("pending", getattr(group, "visual_shape", group))
        if pending_key in cache:
            return dict(cache[pending_key]), where
        world.create_pending_body(obj.state_row)  # this one alone, to measure its shape
        body = obj.raw_body_id
    if body < 0:
        return dict(_MARKER), where
    shape = _measure(body, client, cache)
    if pending_key is not None:
        cache[pending_key] = shape
    return dict(shape), where


def _measure(
    body: int, client: int, cache: dict[tuple[Any, ...], dict[str, Any]]
) -> dict[str, Any]:
    visuals = p.getVisualShapeData(body, physicsClientId=client)
    # Links and meshes depend on the body's own joint state and AABB: computed every time.
    key = (
        tuple(v[1:] for v in visuals)
        if all(v[1] < 0 and v[2] != _GEOM_MESH for v in visuals)
        else None
    )
    if key is not None and key in cache:
        return cache[key]
    shape = _footprint(body, visuals, client)
    if key is not None:
        cache[key] = shape
    return shape


def _footprint(body: int, visuals: Any, client: int) -> dict[str, Any]:
    base_inv = None
    if any(v[1] >= 0 for v in visuals):
        base = p.getBasePositionAndOrientation(body, physicsClientId=client)
        base_inv = p.invertTransform(base[0], base[1])
    lows, highs, colours, areas, round_part = [], [], [], [], False
    for v in visuals:
        link, geom, dims, local_pos, local_orn, rgba = v[1], v[2], v[3], v[5], v[6], v[7]
        half = _half_extents(body, link, geom, dims, client)
        if half is None:
            continue
        pos, orn = _part_frame(body, link, local_pos, local_orn, client, base_inv)
        rot = np.asarray(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
        reach = np.abs(rot) @ half  # half extents of the rotated primitive's bounding box
        lows.append(np.asarray(pos) - reach)
        highs.append(np.asarray(pos) + reach)
        colours.append([round(float(c), 4) for c in rgba])
        areas.append(float(reach[0] * reach[1]))
        round_part = geom == _GEOM_SPHERE or (
            geom in (_GEOM_CYLINDER, _GEOM_CAPSULE) and abs(rot[2, 2]) > 0.999
        )
    if not lows:
        return dict(_MARKER)
    lo, hi = np.min(lows, axis=0), np.max(highs, axis=0)
    center = [round(float(c), 5) for c in (lo[:2] + hi[:2]) / 2.0]
    shape: dict[str, Any] = {
        "type": "circle" if (round_part and len(lows) == 1) else "box",
        "center": center,
        "z": [round(float(lo[2]), 5), round(float(hi[2]), 5)],
        "rgba": colours[int(np.argmax(areas))],
    }
    if shape["type"] == "circle":
        shape["radius"] = round(float(hi[0] - lo[0]) / 2.0, 5)
    else:
        shape["half"] = [round(float(h), 5) for h in (hi[:2] - lo[:2]) / 2.0]
    return shape
