"""Per-row collision geometry: body-frame AABBs read once, world AABBs refreshed with numpy.

Each row's body-frame AABB (center offset and half extents) is read from PyBullet when the
collision system first sees the object. Bodies built from one known collision shape (every
shape-based spawn) share it: the shape is measured once, on the first body made from it, and
every other body of that shape copies the result, so registering 10,000 identical robots costs
one PyBullet measurement, not 10,000. After that a row's world AABB is ``center = p + R c``,
``half = |R| h``, computed only for rows that moved (unrotated rows skip the rotation). STATIC
rows keep the AABB they were registered with. Articulated bodies (URDF with joints) are the
exception: their links move relative to the base, so their AABBs are read from PyBullet
whenever they move; a URDF robot still waiting for its body (``world/urdf_models.py``) moves
rigidly, bounded by its model's box, until the body exists.

World AABBs are stored already padded by ``pad`` (half the closest-points margin) on every side,
which is what the broad phase tests; :meth:`CollisionGeometry.unpadded` gives them back as
PyBullet reports them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import pybullet as p

from fleet_async.core.geometry.quaternions import rotate_vectors_batch
from fleet_async.core.world.pending import PENDING_BODY
from fleet_async.core.world.shapes import body_collision_shape
from fleet_async.core.world.state import COLLISION_CODES, KinematicState

if TYPE_CHECKING:
    from fleet_async.core.world.world import World

__all__ = ["CollisionGeometry"]

_STATIC = COLLISION_CODES["static"]
_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])

# (center, half, box?, box center, box half) of one collision shape in its body's frame.
_ShapeInfo = tuple[np.ndarray, np.ndarray, bool, np.ndarray, np.ndarray]


def _abs_rotation(quats: np.ndarray) -> np.ndarray:
    """(N, 3, 3) element-wise absolute rotation matrices of (x, y, z, w) quaternions."""
    x, y, z, w = quats[:, 0], quats[:, 1], quats[:, 2], quats[:, 3]
    r = np.empty((len(quats), 3, 3))
    r[:, 0, 0] = 1 - 2 * (y * y + z * z)
    r[:, 0, 1] = 2 * (x * y - z * w)
    r[:, 0, 2] = 2 * (x * z + y * w)
    r[:, 1, 0] = 2 * (x * y + z * w)
    r[:, 1, 1] = 1 - 2 * (x * x + z * z)
    r[:, 1, 2] = 2 * (y * z - x * w)
    r[:, 2, 0] = 2 * (x * z - y * w)
    r[:, 2, 1] = 2 * (y * z + x * w)
    r[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return np.abs(r)


class CollisionGeometry:
    """Body-frame and world AABBs, single shapes and boxes of every row.

    Args:
        pad: Metres added to every side of the world AABBs (half the closest-points margin).
        client: Returns the PyBullet client id (without creating pending bodies).
        sync_rows: Pushes the given rows' poses to PyBullet (before reading bodies there).
        world: Pending bodies: their shapes, and creating one to measure its shape.

    Attributes (row-indexed, grown with the store):
        owner: Object id the row was registered for (-1: none).
        mode: Collision code at registration.
        articulated: The body has links (AABB read from PyBullet when it moves).
        shape: The single collision shape the body is, or -1.
        box: The body is one box shape, unrotated in its frame.
        box_center, box_half: That box in the body frame.
        exact: The body is such a box and is unrotated now (as of its last refresh): its
            distance to another such body is computed exactly with numpy.
        aabb_min, aabb_max: Padded world AABBs.
    """

    def __init__(
        self,
        pad: float,
        client: Callable[[], int],
        sync_rows: Callable[[np.ndarray], None],
        world: World,
    ) -> None:
        self.pad = pad
        self._client = client
        self._sync_rows = sync_rows
        self._world = world
        self._cap = 0
        self.owner = np.zeros(0, dtype=np.int64)
        self.mode = np.zeros(0, dtype=np.int8)
        self.articulated = np.zeros(0, dtype=bool)
        self.shape = np.zeros(0, dtype=np.int64)
        self.box = np.zeros(0, dtype=bool)
        self.box_center = np.zeros((0, 3))
        self.box_half = np.zeros((0, 3))
        self.exact = np.zeros(0, dtype=bool)
        self.center = np.zeros((0, 3))  # body-frame AABB center offset
        self.half = np.zeros((0, 3))  # body-frame AABB half extents
        # Minima and maxima as one (2, rows, 3) array, so one numpy call covers both; the
        # *_min / *_max names are its two (rows, 3) halves. lo_off / hi_off: center -/+ half
        # -/+ pad, unrotated.
        self.offsets = np.zeros((2, 0, 3))
        self.aabb = np.zeros((2, 0, 3))
        self._views()
        self._shapes: dict[int, _ShapeInfo] = {}
        self.registrations = 0

    def reset(self) -> None:
        """Forget every registration (simulation reset; shape ids die with the world)."""
        self.owner[:] = -1
        self._shapes.clear()

    def reserve(self, n: int) -> None:
        """Grow the row arrays to hold ``n`` rows."""
        if n <= self._cap:
            return
        cap = max(n, 2 * self._cap, 64)
        for name, width, dtype, fill in (
            ("owner", 0, np.int64, -1),
            ("mode", 0, np.int8, 0),
            ("articulated", 0, bool, False),
            ("shape", 0, np.int64, -1),
            ("box", 0, bool, False),
            ("box_center", 3, float, 0.0),
            ("box_half", 3, float, 0.0),
            ("exact", 0, bool, False),
            ("center", 3, float, 0.0),
            ("half", 3, float, 0.0),
        ):
            old = getattr(self, name)
            new = np.full((cap, width) if width else cap, fill, dtype=dtype)
            new[: len(old)] = old
            setattr(self, name, new)
        for name in ("offsets", "aabb"):
            old = getattr(self, name)
            new = np.zeros((2, cap, 3))
            new[:, : old.shape[1]] = old
            setattr(self, name, new)
        self._cap = cap
        self._views()

    def _views(self) -> None:
        self.lo_off, self.hi_off = self.offsets[0], self.offsets[1]
        self.aabb_min, self.aabb_max = self.aabb[0], self.aabb[1]

    # ----- registration -------------------------------------------------------------------

    def register(self, rows: np.ndarray, store: KinematicState) -> None:
        """Read body-frame geometry for rows new to the collision system, then their AABBs.

        Rows whose body is still pending need no body: their collision shape is known, and
        only the first body of a shape not measured before is created, to measure it.
        """
        client = self._client()
        world = self._world
        bodies = store.body_id[rows].tolist()
        shapes = [
            body_collision_shape(client, b) if b >= 0 else world.pending_collision_shape(row)
            for row, b in zip(rows.tolist(), bodies, strict=True)
        ]
        by_shape: dict[int, list[int]] = {}
        by_model: dict[object, list[int]] = {}
        for row, body, shape in zip(rows.tolist(), bodies, shapes, strict=True):
            if shape >= 0:
                by_shape.setdefault(shape, []).append(row)
            elif body == PENDING_BODY and world.pending_urdf_frame(row) is not None:
                by_model.setdefault(world.pending_group(row), []).append(row)
            else:
                if body == PENDING_BODY:  # a pending body without a collision shape
                    world.create_pending_body(row)
                    body = int(store.body_id[row])
                self._register_one(row, body, store, client)
        for members in by_model.values():  # URDF robots waiting for their bodies
            r = np.array(members, dtype=np.int64)
            frame = world.pending_urdf_frame(members[0])
            assert frame is not None  # grouped by it above
            self.articulated[r] = True  # their model's box (joints at rest) until then
            self.shape[r] = -1
            self.box[r] = False
            self._set_frame(r, *frame)
        for shape, members in by_shape.items():
            info = self._shapes.get(shape)
            if info is None:
                first = members[0]
                if store.body_id[first] == PENDING_BODY:
                    world.create_pending_body(first)
                info = self._register_one(first, store.body_id[first], store, client)
                self._shapes[shape] = info
            r = np.array(members, dtype=np.int64)
            center, half, box, box_center, box_half = info
            self.articulated[r] = False
            self.shape[r] = shape
            self.box[r] = box
            self.box_center[r] = box_center
            self.box_half[r] = box_half
            self._set_frame(r, center, half)
        self.owner[rows] = store.object_id[rows]
        self.mode[rows] = store.collision_mode[rows]
        self.registrations += len(rows)
        self.refresh(rows, store, force=True)

    def _set_frame(self, rows: np.ndarray | int, center: np.ndarray, half: np.ndarray) -> None:
        self.center[rows] = center
        self.half[rows] = half
        self.lo_off[rows] = center - half - self.pad
        self.hi_off[rows] = center + half + self.pad

    def _register_one(self, row: int, body: int, store: KinematicState, client: int) -> _ShapeInfo:
        """Measure one row's body in PyBullet (at identity orientation, in its body frame)."""
        body = int(body)
        pos = store.position[row]
        orn = store.orientation[row]
        if body >= 0:
            self._sync_rows(np.array([row]))
        n_links = p.getNumJoints(body, physicsClientId=client) if body >= 0 else 0
        self.articulated[row] = n_links > 0
        self.shape[row] = body_collision_shape(client, body) if n_links == 0 else -1
        self.box[row] = False
        if body >= 0 and n_links == 0:
            self._read_box(row, body, client)
        lo, hi = self.body_aabb(body, n_links, client) if body >= 0 else (pos, pos)
        if body >= 0 and n_links == 0 and not np.array_equal(orn, _IDENTITY):
            # Read the AABB at identity orientation to get it in the body frame.
            p.resetBasePositionAndOrientation(
                body, pos.tolist(), [0, 0, 0, 1], physicsClientId=client
            )
            lo, hi = self.body_aabb(body, 0, client)
            p.resetBasePositionAndOrientation(
                body, pos.tolist(), orn.tolist(), physicsClientId=client
            )
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        center, half = (lo + hi) / 2 - pos, (hi - lo) / 2
        self._set_frame(row, center, half)
        return (
            center,
            half,
            bool(self.box[row]),
            self.box_center[row].copy(),
            self.box_half[row].copy(),
        )

    def _read_box(self, row: int, body: int, client: int) -> None:
        """Record the body's box if it is exactly one box shape with no rotation in its frame."""
        data = p.getCollisionShapeData(body, -1, physicsClientId=client)
        if len(data) != 1 or data[0][2] != p.GEOM_BOX:
            return
        if not np.array_equal(data[0][6], [0.0, 0.0, 0.0, 1.0]):
            return
        self.box[row] = True
        self.box_center[row] = data[0][5]
        self.box_half[row] = np.asarray(data[0][3], dtype=float) / 2

    @staticmethod
    def body_aabb(body: int, n_links: int, client: int) -> tuple[np.ndarray, np.ndarray]:
        """Union of the AABBs of a body's base and links, as PyBullet reports them."""
        boxes = [p.getAABB(body, link, physicsClientId=client) for link in range(-1, n_links)]
        lo = np.min([b[0] for b in boxes], axis=0)
        hi = np.max([b[1] for b in boxes], axis=0)
        return lo, hi

    # ----- world AABBs --------------------------------------------------------------------

    def refresh(self, rows: np.ndarray, store: KinematicState, force: bool = False) -> None:
        """Recompute the world AABBs of ``rows`` (STATIC rows only when ``force``) and their
        ``exact`` flags."""
        if not len(rows):
            return
        quats = store.orientation.take(rows, axis=0)
        upright = (quats[:, 3] == 1.0) & ~quats[:, :3].any(axis=1)  # identity: no rotation work
        self.exact[rows] = upright & self.box[rows]  # never set for articulated rows
        if not force:
            keep = self.mode[rows] != _STATIC
            if np.count_nonzero(keep) < keep.size:
                rows, quats, upright = rows[keep], quats[keep], upright[keep]
                if not len(rows):
                    return
        art = self.articulated[rows]
        if np.count_nonzero(art):
            # URDF robots still waiting for their bodies move rigidly (their joints cannot
            # have moved): the model's box, like any single body's, below.
            art &= store.body_id.take(rows) != PENDING_BODY
        if np.count_nonzero(art):
            client = self._client()
            self._sync_rows(rows[art])
            for row in rows[art].tolist():
                body = int(store.body_id[row])
                lo, hi = self.body_aabb(body, p.getNumJoints(body, physicsClientId=client), client)
                self.aabb_min[row], self.aabb_max[row] = lo - self.pad, hi + self.pad
            rows, quats, upright = rows[~art], quats[~art], upright[~art]
            if not len(rows):
                return
        if np.count_nonzero(upright) == upright.size:
            self.aabb[:, rows] = store.position.take(rows, axis=0) + self.offsets.take(rows, axis=1)
            return
        if np.count_nonzero(upright):
            r = rows[upright]
            pos = store.position[r]
            self.aabb_min[r] = pos + self.lo_off[r]
            self.aabb_max[r] = pos + self.hi_off[r]
        r, q = rows[~upright], quats[~upright]
        center = store.position[r] + rotate_vectors_batch(self.center[r], q)
        half = np.einsum("nij,nj->ni", _abs_rotation(q), self.half[r]) + self.pad
        self.aabb_min[r] = center - half
        self.aabb_max[r] = center + half

    def refresh_all(self, high: int, store: KinematicState) -> bool:
        """Recompute every row below ``high`` at once when all are unrotated; return whether
        that was possible (the caller then need not refresh moved rows one set at a time).

        Only for simulations with no STATIC and no articulated rows: rows that are not live
        get meaningless AABBs, which nobody reads.
        """
        quats = store.orientation[:high]
        if np.count_nonzero(quats[:, :3]) or np.count_nonzero(quats[:, 3] != 1.0):
            return False
        np.add(store.position[:high], self.offsets[:, :high], out=self.aabb[:, :high])
        self.exact[:high] = self.box[:high]
        return True

    def unpadded(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World AABBs of ``rows`` without the pad, as (min (N, 3), max (N, 3))."""
        # ``take`` along rows: several times faster than ``aabb_min[rows]`` on (N, 3) arrays.
        return self.aabb_min.take(rows, axis=0) + self.pad, self.aabb_max.take(
            rows, axis=0
        ) - self.pad
