"""Narrow phase: which candidate pairs really touch, at the end of the step or during it.

Two single-box bodies at identity orientation (box robots, totes and pallets driving straight)
get their exact distance in one numpy pass. Other distance queries on two bodies that are each
one known collision shape go to PyBullet as (shape, pose from the state store), so those rows
are never pushed just for the query; the rest push their rows and ask about the bodies.

The swept test (``SimulationParams.collision_sweep``) asks whether two objects came within the
margin at any time between the previous check and this one, each moving on the straight line
between its two positions (orientations as at this check): exact for unrotated boxes (per-axis
intervals of overlap in time, intersected; a pair that never overlaps but comes within the
margin on every axis has its true distance minimised over time), and for other shapes the pair
is measured at the time its AABB centres came closest.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pybullet as p

from fleet_async.core.base.types import CollisionDetectionMethod
from fleet_async.core.collision.geometry import CollisionGeometry
from fleet_async.core.world.pending import PENDING_BODY
from fleet_async.core.world.state import COLLISION_CODES, KinematicState

__all__ = ["NarrowPhase"]

_FLAT = COLLISION_CODES["normal_2d"]


class NarrowPhase:
    """Distance and contact tests for candidate row pairs.

    Args:
        geometry: The rows' collision geometry.
        method: CLOSEST_POINTS, CONTACT_POINTS or HYBRID.
        margin: Distance (m) at which CLOSEST_POINTS reports a pair.
        client: Returns the PyBullet client id (without creating pending bodies).
        sync_rows: Pushes the given rows' poses to PyBullet.
        create_bodies: Creates the bodies the given rows wait for (before a query that
            needs bodies; ``World.create_pending_bodies_for``).
    """

    def __init__(
        self,
        geometry: CollisionGeometry,
        method: CollisionDetectionMethod,
        margin: float,
        client: Callable[[], int],
        sync_rows: Callable[[np.ndarray], None],
        create_bodies: Callable[[np.ndarray], None],
    ) -> None:
        self._geo = geometry
        self.method = method
        self.margin = margin
        self._client = client
        self._sync_rows = sync_rows
        self._create_bodies = create_bodies

    def touching(
        self,
        row_pairs: np.ndarray,
        store: KinematicState,
        positions: np.ndarray | None = None,
        aabb_checked: bool = False,
    ) -> np.ndarray:
        """(K,) bool: whether each candidate pair touches.

        Args:
            row_pairs: (K, 2) rows.
            store: The state store (orientations, and positions unless given).
            positions: (K, 2, 3) positions to test the pairs at instead of the store's (the
                swept test's time of closest approach); bodies are then queried by shape or
                exactly, never by pushing rows, and the AABB test is skipped.
            aabb_checked: The pairs' AABBs are known to overlap (skip that test).
        """
        k = len(row_pairs)
        if not k:
            return np.zeros(0, dtype=bool)
        geo = self._geo
        pos = store.position.take(row_pairs, axis=0) if positions is None else positions
        if self.method is CollisionDetectionMethod.CLOSEST_POINTS or positions is not None:
            contact = None
            ok = geo.exact[row_pairs]
            exact = ok[:, 0] & ok[:, 1]
            if np.count_nonzero(exact) == exact.size:
                # The common case for box fleets: no PyBullet, no AABB test.
                return self._box_distance(row_pairs, pos) <= self.margin
        else:
            if self.method is CollisionDetectionMethod.CONTACT_POINTS:
                contact = np.ones(k, dtype=bool)
            else:  # HYBRID: contact points between dynamic bodies, distances otherwise
                contact = ~store.kinematic[row_pairs].any(axis=1)
            ok = geo.exact[row_pairs]
            exact = ok[:, 0] & ok[:, 1] & ~contact
        out = np.zeros(k, dtype=bool)
        if np.count_nonzero(exact):
            out[exact] = self._box_distance(row_pairs[exact], pos[exact]) <= self.margin
        rest = (~exact).nonzero()[0]
        if positions is None and not aabb_checked:
            rest = rest[self.aabbs_overlap(row_pairs[rest])]
        if len(rest):
            self._query(row_pairs, rest, pos, contact, positions is not None, store, out)
        return out

    def aabbs_overlap(self, row_pairs: np.ndarray) -> np.ndarray:
        """(K,) bool: whether each pair's padded world AABBs overlap (Z ignored for pairs with
        a NORMAL_2D side)."""
        geo = self._geo
        lo, hi = geo.aabb_min[row_pairs], geo.aabb_max[row_pairs]  # (K, 2, 3)
        sep = (lo[:, 0] > hi[:, 1]) | (lo[:, 1] > hi[:, 0])
        flat = geo.mode[row_pairs] == _FLAT
        sep[:, 2] &= ~(flat[:, 0] | flat[:, 1])
        return ~sep.any(axis=1)

    def _query(
        self,
        row_pairs: np.ndarray,
        rest: np.ndarray,
        pos: np.ndarray,
        contact: np.ndarray | None,
        swept: bool,
        store: KinematicState,
        out: np.ndarray,
    ) -> None:
        """Ask PyBullet about the pairs ``rest`` (indices into ``row_pairs``); fill ``out``."""
        shapes = self._geo.shape[row_pairs[rest]]
        known = (shapes >= 0).all(axis=1)
        if contact is not None:
            known &= ~contact[rest]
        if swept:
            known[:] = True  # the swept test never moves bodies in PyBullet
        needs_body = row_pairs[rest[~known]]
        client = self._client()
        if len(needs_body):
            if np.count_nonzero(store.body_id[needs_body] == PENDING_BODY):
                self._create_bodies(np.unique(needs_body))
            self._sync_rows(np.unique(needs_body))
        bodies = store.body_id[row_pairs[rest]].tolist()
        pos_l = pos[rest].tolist()
        orn_l = store.orientation[row_pairs[rest]].tolist()
        margin = self.margin
        for i, k in enumerate(rest.tolist()):
            a, b = bodies[i]
            if contact is not None and contact[k]:
                out[k] = len(p.getContactPoints(a, b, physicsClientId=client)) > 0
            elif known[i]:
                if shapes[i, 0] < 0 or shapes[i, 1] < 0:
                    continue  # compound bodies have no swept test; their end poses decide
                hits = p.getClosestPoints(
                    -1,
                    -1,
                    margin,
                    collisionShapeA=int(shapes[i, 0]),
                    collisionShapeB=int(shapes[i, 1]),
                    collisionShapePositionA=pos_l[i][0],
                    collisionShapePositionB=pos_l[i][1],
                    collisionShapeOrientationA=orn_l[i][0],
                    collisionShapeOrientationB=orn_l[i][1],
                    physicsClientId=client,
                )
                out[k] = len(hits) > 0
            else:
                out[k] = len(p.getClosestPoints(a, b, margin, physicsClientId=client)) > 0

    def _unrotated_boxes(self, row_pairs: np.ndarray) -> np.ndarray:
        """Pairs whose two bodies are single boxes at identity orientation (exact distance)."""
        ok = self._geo.exact[row_pairs]
        return ok[:, 0] & ok[:, 1]

    def _box_distance(self, row_pairs: np.ndarray, pos: np.ndarray) -> np.ndarray:
        """Exact distance (m) between two axis-aligned boxes per pair (0 when they overlap).

        Matches PyBullet's closest-points distance for unrotated box shapes, without a call
        per pair. ``pos``: (K, 2, 3) the two bodies' positions.
        """
        geo = self._geo
        center = pos + geo.box_center.take(row_pairs, axis=0)
        half = geo.box_half.take(row_pairs, axis=0)
        gap = np.abs(center[:, 0] - center[:, 1]) - half[:, 0] - half[:, 1]
        np.maximum(gap, 0.0, out=gap)
        gap *= gap
        return np.sqrt(gap.sum(axis=1))

    # ----- swept test -----------------------------------------------------------------------

    def touched_during(
        self, row_pairs: np.ndarray, store: KinematicState, start: np.ndarray
    ) -> np.ndarray:
        """(K,) bool: whether each pair came within the margin while moving from ``start`` to
        the store's positions, each object on a straight line (orientations: the store's).

        Args:
            row_pairs: (K, 2) rows.
            store: The state store (the end poses).
            start: (capacity, 3) row positions at the previous check.
        """
        out = np.zeros(len(row_pairs), dtype=bool)
        if not len(row_pairs):
            return out
        a, b = row_pairs[:, 0], row_pairs[:, 1]
        rel0 = start[b] - start[a]  # b relative to a at the start
        move = (store.position[b] - store.position[a]) - rel0
        boxes = self._unrotated_boxes(row_pairs)
        if np.count_nonzero(boxes):
            geo = self._geo
            ab, bb = a[boxes], b[boxes]
            rel = rel0[boxes] + geo.box_center[bb] - geo.box_center[ab]
            half = geo.box_half[ab] + geo.box_half[bb]
            mv = move[boxes]
            hit = _overlap_in_time(rel, mv, half)  # the boxes overlapped: exact
            near = ~hit & _overlap_in_time(rel, mv, half + self.margin)
            if np.count_nonzero(near):  # within the margin per axis: measure the Euclidean distance
                hit[near] = _within(rel[near], mv[near], half[near], self.margin)
            out[boxes] = hit
        rest = ~boxes
        if np.count_nonzero(rest):
            # Time of closest approach of the two AABB centres on their straight paths.
            d0, dv = rel0[rest], move[rest]
            speed2 = (dv * dv).sum(axis=1)
            t = np.ones(len(d0))
            moving = speed2 > 0
            t[moving] = np.clip(-(d0[moving] * dv[moving]).sum(axis=1) / speed2[moving], 0, 1)
            r = row_pairs[rest]
            begin = start[r]
            at = begin + (store.position[r] - begin) * t[:, None, None]
            out[rest] = self.touching(r, store, positions=at)
        return out


def _overlap_in_time(rel0: np.ndarray, move: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Whether ``|rel0 + t move| <= reach`` on every axis for one t in [0, 1] (per row).

    Each axis gives an interval of t in which the boxes overlap along it; the boxes touch when
    the three intervals and [0, 1] have a common point.
    """
    still = move == 0.0
    safe = np.where(still, 1.0, move)
    t_a = (-reach - rel0) / safe
    t_b = (reach - rel0) / safe
    inside = np.abs(rel0) <= reach
    enter = np.where(still, np.where(inside, 0.0, np.inf), np.minimum(t_a, t_b))
    leave = np.where(still, np.where(inside, 1.0, -np.inf), np.maximum(t_a, t_b))
    first = np.maximum(enter.max(axis=1), 0.0)
    last = np.minimum(leave.min(axis=1), 1.0)
    return first <= last


def _within(rel0: np.ndarray, move: np.ndarray, half: np.ndarray, margin: float) -> np.ndarray:
    """Whether boxes whose centres are ``rel0 + t move`` apart come within ``margin`` for
    some t in [0, 1] (per row).

    The distance is convex in t (a norm of convex functions of t), so a golden-section search
    closes in on its minimum; it changes by at most ``|move|`` per unit of t, so a row is
    decided as soon as a point within the margin is found or the bracket's best point minus
    ``|move|`` times its width is beyond it. Rows not decided after 40 rounds (t to 1e-8)
    take the best point found.
    """

    def dist(t: np.ndarray) -> np.ndarray:
        gap = np.maximum(np.abs(rel0 + t[:, None] * move) - half, 0.0)
        return np.sqrt((gap * gap).sum(axis=1))

    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    k = len(rel0)
    speed = np.sqrt((move * move).sum(axis=1))
    lo, hi = np.zeros(k), np.ones(k)
    c, d = hi - ratio, lo + ratio
    fc, fd = dist(c), dist(d)
    best = np.minimum(np.minimum(fc, fd), np.minimum(dist(lo), dist(hi)))
    for _ in range(40):
        if ((best <= margin) | (best - speed * (hi - lo) > margin)).all():
            break
        left = fc <= fd  # the minimum lies in [lo, d]: d becomes the new hi
        hi = np.where(left, d, hi)
        lo = np.where(left, lo, c)
        kept, fkept = np.where(left, c, d), np.where(left, fc, fd)
        new = np.where(left, hi - ratio * (hi - lo), lo + ratio * (hi - lo))
        fnew = dist(new)
        best = np.minimum(best, fnew)
        c, fc = np.where(left, new, kept), np.where(left, fnew, fkept)
        d, fd = np.where(left, kept, new), np.where(left, fkept, fnew)
    return best <= margin
