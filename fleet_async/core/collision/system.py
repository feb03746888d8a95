"""Collision detection: AABBs from the state store, broad phase, narrow phase, events.

Each object's body-frame AABB (center offset and half extents) is read from PyBullet once,
when the collision system first sees the object. After that its world AABB is computed from
the state store with numpy (``center = p + R c``, ``half = |R| h``), only for rows that moved;
STATIC objects keep the AABB they were registered with, DISABLED objects have none.
Articulated bodies (URDF with joints) are the exception: their links move relative to the
base, so their AABBs are read from PyBullet whenever they move.

A check then runs: broad phase over pairs involving a moved object (``broadphase.py``), AABB
overlap, and the narrow phase on the survivors only, after pushing just their rows to
PyBullet. Pairs that involve no moved object keep their state, so active pairs are tracked
incrementally and ``collision_started`` / ``collision_ended`` fire once per contact.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import pybullet as p

from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.types import CollisionDetectionMethod, SpatialHashCellSizeMode
from fleet_async.core.collision.broadphase import aabb_overlap, auto_cell_size, candidate_pairs
from fleet_async.core.geometry.quaternions import rotate_vectors_batch
from fleet_async.core.world.shapes import body_collision_shape
from fleet_async.core.world.state import COLLISION_CODES

if TYPE_CHECKING:
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["CollisionListener", "CollisionSystem"]

CollisionListener = Callable[[list[tuple[int, int]], list[tuple[int, int]]], None]
"""Called as ``listener(ended, started)`` once per check that changed the active pairs."""

_STATIC = COLLISION_CODES["static"]
_DISABLED = COLLISION_CODES["disabled"]
_FLAT = COLLISION_CODES["normal_2d"]


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


class CollisionSystem:
    """Collision state and checks of one simulation."""

    def __init__(
        self, sim: MultiRobotSimulationCore, on_sync: Callable[[np.ndarray], None]
    ) -> None:
        self._sim = sim
        self._sync_rows = on_sync
        prm = sim.params
        self.frequency = prm.collision_check_frequency
        self.cell_mode = prm.spatial_hash_cell_size_mode
        self.cell_size: float | None = prm.spatial_hash_cell_size
        self.method = prm.resolved_collision_detection_method
        self.margin = prm.collision_margin
        self.multi_cell_threshold = prm.multi_cell_threshold
        self.ignore_static = prm.ignore_static_collision
        self.color_change = prm.enable_collision_color_change
        self._cap = 0
        self._center = np.zeros((0, 3))  # body-frame AABB center offset
        self._half = np.zeros((0, 3))  # body-frame AABB half extents
        self._aabb_min = np.zeros((0, 3))
        self._aabb_max = np.zeros((0, 3))
        self._owner = np.zeros(0, dtype=np.int64)  # object id the row was registered for
        self._mode = np.zeros(0, dtype=np.int8)  # collision code at registration
        self._articulated = np.zeros(0, dtype=bool)
        self._shape = np.zeros(0, dtype=np.int64)  # single collision shape id, or -1
        self._box = np.zeros(0, dtype=bool)  # the body is one box shape, unrotated in its frame
        self._box_center = np.zeros((0, 3))  # that box's center in the body frame
        self._box_half = np.zeros((0, 3))  # and its half extents
        self._active: set[tuple[int, int]] = set()
        self._colors: dict[int, list[Any]] = {}
        self._next_due_step = 0
        self.registrations = 0
        self.listeners: list[CollisionListener] = []
        """Told the pairs (object ids, a < b, sorted) that ended and started, once per check."""

    # ----- schedule -----------------------------------------------------------------------

    def set_frequency(self, frequency: float | None) -> None:
        """None: every step; 0: never; f > 0: at f Hz of sim time."""
        if frequency is not None and not (isinstance(frequency, (int, float)) and frequency >= 0):
            raise ValueError(
                f"collision_check_frequency: expected None or a number >= 0 (Hz), got {frequency!r}"
            )
        self.frequency = frequency
        self._next_due_step = 0

    def is_due(self, step: int, timestep: float) -> bool:
        """Whether the check runs in ``step`` (0-based)."""
        if self.frequency is None:
            return True
        if self.frequency == 0:
            return False
        if step < self._next_due_step:
            return False
        period_steps = max(1, round(1.0 / (self.frequency * timestep)))
        self._next_due_step = step + period_steps
        return True

    def reset(self) -> None:
        """Forget every registration and active pair (simulation reset)."""
        self._owner[:] = -1
        self._active.clear()
        self._colors.clear()
        self._next_due_step = 0
        if self.cell_mode is not SpatialHashCellSizeMode.CONSTANT:
            self.cell_size = None

    # ----- AABBs --------------------------------------------------------------------------

    def _reserve(self, n: int) -> None:
        if n <= self._cap:
            return
        cap = max(n, 2 * self._cap, 64)
        for name, width, dtype, fill in (
            ("_center", 3, float, 0.0),
            ("_half", 3, float, 0.0),
            ("_aabb_min", 3, float, 0.0),
            ("_aabb_max", 3, float, 0.0),
            ("_owner", 0, np.int64, -1),
            ("_mode", 0, np.int8, 0),
            ("_articulated", 0, bool, False),
            ("_shape", 0, np.int64, -1),
            ("_box", 0, bool, False),
            ("_box_center", 3, float, 0.0),
            ("_box_half", 3, float, 0.0),
        ):
            old = getattr(self, name)
            new = np.full((cap, width) if width else cap, fill, dtype=dtype)
            new[: len(old)] = old
            setattr(self, name, new)
        self._cap = cap

    def _register(self, rows: np.ndarray) -> None:
        """Read body-frame AABBs from PyBullet for rows new to the collision system."""
        store, client = self._sim.state, self._sim.client
        self._sync_rows(rows)
        for row in rows.tolist():
            body = int(store.body_id[row])
            pos = store.position[row]
            orn = store.orientation[row]
            n_links = p.getNumJoints(body, physicsClientId=client) if body >= 0 else 0
            self._articulated[row] = n_links > 0
            self._shape[row] = body_collision_shape(client, body) if n_links == 0 else -1
            self._box[row] = False
            if body >= 0 and n_links == 0:
                self._read_box(row, body, client)
            lo, hi = self._body_aabb(body, n_links, client) if body >= 0 else (pos, pos)
            identity = np.array_equal(orn, [0.0, 0.0, 0.0, 1.0])
            if not identity and body >= 0 and n_links == 0:
                # Read the AABB at identity orientation to get it in the body frame.
                p.resetBasePositionAndOrientation(
                    body, pos.tolist(), [0, 0, 0, 1], physicsClientId=client
                )
                lo, hi = self._body_aabb(body, 0, client)
                p.resetBasePositionAndOrientation(
                    body, pos.tolist(), orn.tolist(), physicsClientId=client
                )
            lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
            self._center[row] = (lo + hi) / 2 - pos
            self._half[row] = (hi - lo) / 2
            self._owner[row] = store.object_id[row]
            self._mode[row] = store.collision_mode[row]
            self.registrations += 1
        self._refresh(rows, force=True)

    def _read_box(self, row: int, body: int, client: int) -> None:
        """Record the body's box if it is exactly one box shape with no rotation in its frame."""
        data = p.getCollisionShapeData(body, -1, physicsClientId=client)
        if len(data) != 1 or data[0][2] != p.GEOM_BOX:
            return
        if not np.array_equal(data[0][6], [0.0, 0.0, 0.0, 1.0]):
            return
        self._box[row] = True
        self._box_center[row] = data[0][5]
        self._box_half[row] = np.asarray(data[0][3], dtype=float) / 2

    @staticmethod
    def _body_aabb(body: int, n_links: int, client: int) -> tuple[np.ndarray, np.ndarray]:
        boxes = [p.getAABB(body, link, physicsClientId=client) for link in range(-1, n_links)]
        lo = np.min([b[0] for b in boxes], axis=0)
        hi = np.max([b[1] for b in boxes], axis=0)
        return lo, hi

    def _refresh(self, rows: np.ndarray, force: bool = False) -> None:
        """Recompute world AABBs of moved rows (STATIC rows only when ``force``)."""
        if not force:
            rows = rows[self._mode[rows] != _STATIC]
        if not len(rows):
            return
        art = self._articulated[rows]
        if art.any():
            store, client = self._sim.state, self._sim.client
            self._sync_rows(rows[art])
            for row in rows[art].tolist():
                body = int(store.body_id[row])
                lo, hi = self._body_aabb(body, p.getNumJoints(body, physicsClientId=client), client)
                self._aabb_min[row], self._aabb_max[row] = lo, hi
            rows = rows[~art]
        if not len(rows):
            return
        store = self._sim.state
        quats = store.orientation[rows]
        upright = (quats[:, 3] == 1.0) & ~quats[:, :3].any(axis=1)  # identity: no rotation work
        if upright.any():
            r = rows[upright]
            center = store.position[r] + self._center[r]
            self._aabb_min[r] = center - self._half[r]
            self._aabb_max[r] = center + self._half[r]
        if not upright.all():
            r, q = rows[~upright], quats[~upright]
            center = store.position[r] + rotate_vectors_batch(self._center[r], q)
            half = np.einsum("nij,nj->ni", _abs_rotation(q), self._half[r])
            self._aabb_min[r] = center - half
            self._aabb_max[r] = center + half

    def prepare_rows(self) -> np.ndarray:
        """Register and refresh as a check would; return the rows taking part."""
        return self._prepare()

    def _prepare(self) -> np.ndarray:
        """Register new / changed rows, refresh moved ones; return the rows taking part."""
        store = self._sim.state
        high = store.high_water
        self._reserve(store.capacity)
        live = store.active[:high]
        stale = live & (
            (self._owner[:high] != store.object_id[:high])
            | (self._mode[:high] != store.collision_mode[:high])
        )
        stale &= store.collision_mode[:high] != _DISABLED
        new_rows = np.flatnonzero(stale)
        if len(new_rows):
            self._register(new_rows)
        self._mode[:high] = np.where(live, store.collision_mode[:high], self._mode[:high])
        moved = np.flatnonzero(live & store.moved[:high])
        self._refresh(moved)
        return np.flatnonzero(live & (store.collision_mode[:high] != _DISABLED))

    def bounds(self, rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """(min, max) corners of the union of the AABBs of ``rows`` (default: all taking part)
        that have one; None when none has."""
        taking = self._prepare()
        rows = taking if rows is None else rows[np.isin(rows, taking)]
        if not len(rows):
            return None
        return self._aabb_min[rows].min(axis=0), self._aabb_max[rows].max(axis=0)

    def get_aabbs(self) -> dict[int, tuple[list[float], list[float]]]:
        """``{object_id: (aabb_min, aabb_max)}`` for every object that takes part."""
        rows = self._prepare()
        ids = self._sim.state.object_id[rows]
        return {
            int(i): (self._aabb_min[r].tolist(), self._aabb_max[r].tolist())
            for i, r in zip(ids, rows, strict=True)
        }

    # ----- broad phase --------------------------------------------------------------------

    def resolve_cell_size(self, rows: np.ndarray, recompute: bool = False) -> float:
        """The hash cell size in force, computing it per the cell size mode when needed."""
        if self.cell_mode is SpatialHashCellSizeMode.CONSTANT and self.cell_size:
            return self.cell_size
        adaptive = self.cell_mode is SpatialHashCellSizeMode.AUTO_ADAPTIVE
        if self.cell_size is None or recompute or adaptive:
            self.cell_size = auto_cell_size(self._aabb_min[rows], self._aabb_max[rows])
        return self.cell_size

    def filter_pairs(
        self, ignore_static: bool | None = None, moved_ids: set[int] | None = None
    ) -> tuple[np.ndarray, dict[str, float]]:
        """Rows pairs (i < j) whose AABBs overlap (inflated by the margin), with timings in ms."""
        t0 = time.perf_counter()
        rows = self._prepare()
        t1 = time.perf_counter()
        store = self._sim.state
        if moved_ids is None:
            moved = store.moved[rows]
        else:
            moved = np.isin(
                store.object_id[rows], np.fromiter(moved_ids, dtype=np.int64, count=len(moved_ids))
            )
        pad = self.margin / 2 if self.method is not CollisionDetectionMethod.CONTACT_POINTS else 0.0
        amin, amax = self._aabb_min[rows] - pad, self._aabb_max[rows] + pad
        mode = store.collision_mode[rows]
        flat = mode == _FLAT
        cell = self.resolve_cell_size(rows)
        idx = candidate_pairs(amin, amax, flat, moved, cell, self.multi_cell_threshold)
        t2 = time.perf_counter()
        if len(idx):
            skip_static = self.ignore_static if ignore_static is None else ignore_static
            static_a, static_b = mode[idx[:, 0]] == _STATIC, mode[idx[:, 1]] == _STATIC
            keep = ~(static_a & static_b)
            if skip_static:
                keep &= ~(static_a | static_b)
            idx = idx[keep]
            flat_pair = flat[idx[:, 0]] | flat[idx[:, 1]]
            idx = idx[
                aabb_overlap(
                    amin[idx[:, 0]], amax[idx[:, 0]], amin[idx[:, 1]], amax[idx[:, 1]], flat_pair
                )
            ]
        t3 = time.perf_counter()
        timings = {
            "get_aabbs": (t1 - t0) * 1e3,
            "spatial_hashing": (t2 - t1) * 1e3,
            "aabb_filtering": (t3 - t2) * 1e3,
        }
        return rows[idx] if len(idx) else np.empty((0, 2), dtype=np.int64), timings

    # ----- narrow phase and events -----------------------------------------------------------

    def _touching(self, row_pairs: np.ndarray) -> list[bool]:
        """Narrow phase for candidate row pairs.

        Two single-box bodies at identity orientation (the common case for box robots, totes
        and pallets) get their exact distance in one numpy pass. Other distance queries on two
        bodies that are each one known collision shape go to PyBullet as (shape, pose from the
        store), so those rows are never pushed just for the query; the rest push their rows.
        """
        store, client = self._sim.state, self._sim.client
        if not len(row_pairs):
            return []
        kinematic = store.kinematic[row_pairs]
        if self.method is CollisionDetectionMethod.CONTACT_POINTS:
            contact = np.ones(len(row_pairs), dtype=bool)
        elif self.method is CollisionDetectionMethod.HYBRID:
            contact = ~kinematic.any(axis=1)
        else:
            contact = np.zeros(len(row_pairs), dtype=bool)
        exact = ~contact & self._unrotated_boxes(row_pairs)
        out = np.zeros(len(row_pairs), dtype=bool)
        if exact.any():
            out[exact] = self._box_distance(row_pairs[exact]) <= self.margin
            if exact.all():
                return out.tolist()
        shapes = self._shape[row_pairs]
        by_shape = ~contact & ~exact & (shapes >= 0).all(axis=1)
        needs_body = row_pairs[~by_shape & ~exact]
        if len(needs_body):
            self._sync_rows(np.unique(needs_body))
        bodies = store.body_id[row_pairs].tolist()
        pos = store.position[row_pairs].tolist()
        orn = store.orientation[row_pairs].tolist()
        margin = self.margin
        for k in np.flatnonzero(~exact).tolist():
            a, b = bodies[k]
            if contact[k]:
                out[k] = len(p.getContactPoints(a, b, physicsClientId=client)) > 0
            elif by_shape[k]:
                hits = p.getClosestPoints(
                    -1,
                    -1,
                    margin,
                    collisionShapeA=int(shapes[k, 0]),
                    collisionShapeB=int(shapes[k, 1]),
                    collisionShapePositionA=pos[k][0],
                    collisionShapePositionB=pos[k][1],
                    collisionShapeOrientationA=orn[k][0],
                    collisionShapeOrientationB=orn[k][1],
                    physicsClientId=client,
                )
                out[k] = len(hits) > 0
            else:
                out[k] = len(p.getClosestPoints(a, b, margin, physicsClientId=client)) > 0
        return out.tolist()

    def _unrotated_boxes(self, row_pairs: np.ndarray) -> np.ndarray:
        """Pairs whose two bodies are single boxes at identity orientation (exact distance)."""
        both = self._box[row_pairs].all(axis=1)
        if not both.any():
            return both
        orn = self._sim.state.orientation[row_pairs]  # (K, 2, 4)
        identity = (orn[:, :, 3] == 1.0).all(axis=1) & ~orn[:, :, :3].any(axis=(1, 2))
        return both & identity

    def _box_distance(self, row_pairs: np.ndarray) -> np.ndarray:
        """Exact distance (m) between two axis-aligned boxes per pair (0 when they overlap).

        Matches PyBullet's closest-points distance for unrotated box shapes, without a call
        per pair.
        """
        store = self._sim.state
        a, b = row_pairs[:, 0], row_pairs[:, 1]
        ca = store.position[a] + self._box_center[a]
        cb = store.position[b] + self._box_center[b]
        gap = np.abs(ca - cb) - self._box_half[a] - self._box_half[b]
        return np.sqrt((np.maximum(gap, 0.0) ** 2).sum(axis=1))

    def check(
        self, ignore_static: bool | None = None, collision_color: list[float] | None = None
    ) -> tuple[list[tuple[int, int]], dict[str, float]]:
        """Run one check; return the active pairs (object ids, i < j) and timings in ms."""
        t0 = time.perf_counter()
        store = self._sim.state
        high = store.high_water
        row_pairs, timings = self.filter_pairs(ignore_static)
        t1 = time.perf_counter()
        touching = self._touching(row_pairs)
        t2 = time.perf_counter()
        ids = store.object_id[row_pairs].tolist() if len(row_pairs) else []
        now = {tuple(sorted(pair)) for pair, hit in zip(ids, touching, strict=True) if hit}
        # An active pair ends when it was re-checked (one side moved) and is no longer touching,
        # or when one side left the simulation. Pairs where neither moved keep their state.
        ended = {pair for pair in self._active if pair not in now and self._recheck(pair)}
        started = now - self._active
        self._active = (self._active - ended) | started
        store.moved[:high] = False
        self._emit(sorted(ended), sorted(started), collision_color)
        timings["contact_points"] = (t2 - t1) * 1e3
        timings["total"] = (time.perf_counter() - t0) * 1e3
        return sorted(self._active), timings

    def _recheck(self, pair: tuple[int, int]) -> bool:
        store = self._sim.state
        for object_id in pair:
            obj = self._sim.get_object_by_id(object_id)
            if obj is None or store.moved[obj.state_row]:
                return True
        return False

    def _emit(
        self,
        ended: list[tuple[int, int]],
        started: list[tuple[int, int]],
        color: list[float] | None,
    ) -> None:
        sim = self._sim
        for event, pairs in (
            (SimEvents.COLLISION_ENDED, ended),
            (SimEvents.COLLISION_STARTED, started),
        ):
            for a_id, b_id in pairs:
                obj_a, obj_b = sim.get_object_by_id(a_id), sim.get_object_by_id(b_id)
                sim.events.emit(event, sim=sim, obj_a=obj_a, obj_b=obj_b)
                for me, other in ((obj_a, obj_b), (obj_b, obj_a)):
                    if me is not None and me.has_event_bus():
                        me.events.emit(event, sim=sim, obj_a=obj_a, obj_b=obj_b, other=other)
        if started or ended:
            for listener in tuple(self.listeners):
                listener(ended, started)
        if started:
            sim.note_collisions(len(started))
        if self.color_change and (started or ended):
            self._recolor(color if color is not None else sim.collision_color)

    def _recolor(self, color: list[float]) -> None:
        sim = self._sim
        colliding = {i for pair in self._active for i in pair}
        for object_id in colliding - set(self._colors):
            obj = sim.get_object_by_id(object_id)
            if obj is None or obj.body_id < 0:
                continue
            data = p.getVisualShapeData(obj.body_id, physicsClientId=sim.client)
            self._colors[object_id] = [(d[1], d[7]) for d in data]
            for link, _ in self._colors[object_id]:
                p.changeVisualShape(obj.body_id, link, rgbaColor=color, physicsClientId=sim.client)
        for object_id in set(self._colors) - colliding:
            saved = self._colors.pop(object_id)
            obj = sim.get_object_by_id(object_id)
            if obj is not None:
                for link, rgba in saved:
                    p.changeVisualShape(
                        obj.body_id, link, rgbaColor=list(rgba), physicsClientId=sim.client
                    )

    def active_pairs(self) -> list[tuple[int, int]]:
        """Active pairs (object ids, i < j), sorted."""
        return sorted(self._active)
