"""The safety fields' first evaluation, kept as the reference the fast one is tested against.

Every step, one box per object enters the collision broad phase (``broadphase.candidate_pairs``):
each fielded robot's AABB grown over its warning field (marked moved), every other object's
AABB, a map's obstacle boxes; the candidate pairs are then tested exactly (a rectangle against
a box). Simple and slow (the broad phase sorts and deduplicates every pair of long boxes each
step); ``sim.safety.evaluator = "reference"`` selects it. The fast path (``safety_join.py``)
must give the same hits: the same exact tests on a superset of the pairs that can pass them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from fleet_async.core.collision.broadphase import auto_cell_size, candidate_pairs
from fleet_async.core.collision.safety_geometry import FieldShapes, rect_hits_box

if TYPE_CHECKING:
    from fleet_async.core.collision.safety_state import FieldTable
    from fleet_async.core.collision.system import CollisionSystem

__all__ = ["Hits", "reference_hits"]

Hits = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""(owner entry, obstacle row or -1 for a static box, in protective, in warning) per hit."""

_MULTI_CELL = 16.0  # cells a box may span per axis and still be hashed (a field is long)


def reference_hits(
    table: FieldTable,
    collision: CollisionSystem,
    world: Any,
    static: tuple[np.ndarray, np.ndarray],
    transparent: set[int],
    shapes: FieldShapes,
    active: np.ndarray,
) -> Hits:
    """Every obstacle in an active field, by the generic broad phase (see the module doc)."""
    rows = collision.prepare_rows()
    lo, hi = collision.geometry.unpadded(rows) if len(rows) else (np.zeros((0, 3)),) * 2
    if transparent:
        keep = ~np.isin(world.store.object_id[rows], list(transparent))
        rows, lo, hi = rows[keep], lo[keep], hi[keep]
    n_obj = len(rows)
    box_lo = np.concatenate((lo, static[0]))
    box_hi = np.concatenate((hi, static[1]))
    n_box = len(box_lo)
    owners = active.nonzero()[0]
    f_lo, f_hi = shapes.bounds(table.warning_depth)
    f_lo, f_hi = f_lo[owners], f_hi[owners]
    z_lo, z_hi = table.z_band(owners)
    # An owner's own box grows to cover its field (one box per robot, not two); owners
    # without collision geometry get a box of their own after the obstacles'.
    at = np.searchsorted(rows, table.rows[owners])
    own = at < n_obj
    own[own] = rows[at[own]] == table.rows[owners][own]
    place = np.where(own, at, n_box + np.cumsum(~own) - 1)
    extra = int(np.count_nonzero(~own))
    all_lo = np.concatenate((box_lo, np.zeros((extra, 3))))
    all_hi = np.concatenate((box_hi, np.zeros((extra, 3))))
    field_lo = np.column_stack((f_lo, z_lo))
    field_hi = np.column_stack((f_hi, z_hi))
    all_lo[place] = np.where(own[:, None], np.minimum(all_lo[place], field_lo), field_lo)
    all_hi[place] = np.where(own[:, None], np.maximum(all_hi[place], field_hi), field_hi)
    moved = np.zeros(len(all_lo), dtype=bool)
    moved[place] = True
    owner_of = np.full(len(all_lo), -1, dtype=np.int64)
    owner_of[place] = owners
    cell = auto_cell_size(box_lo, box_hi) if n_box else 1.0
    pairs = candidate_pairs(all_lo, all_hi, None, moved, cell, _MULTI_CELL)
    # Each pair is tested both ways: field of one side's owner vs the other side's box.
    a, b = pairs[:, 0], pairs[:, 1]
    ab = (owner_of[a] >= 0) & (b < n_box)
    ba = (owner_of[b] >= 0) & (a < n_box)
    field = np.concatenate((a[ab], b[ba]))
    obstacle = np.concatenate((b[ab], a[ba]))
    owner = owner_of[field]
    zi = np.searchsorted(owners, owner)
    obstacle_row = np.where(obstacle < n_obj, rows[np.minimum(obstacle, n_obj - 1)], -1)
    keep = obstacle_row != table.rows[owner]
    keep &= (box_hi[obstacle, 2] >= z_lo[zi]) & (box_lo[obstacle, 2] <= z_hi[zi])
    keep &= table.not_carried(owner, obstacle_row, world)
    owner, obstacle, obstacle_row = owner[keep], obstacle[keep], obstacle_row[keep]
    # The protective field lies inside the warning field: test it only where that hit.
    u, w, half_w = shapes.u[owner], shapes.w[owner], shapes.half_w[owner]
    b_lo, b_hi = box_lo[obstacle, :2], box_hi[obstacle, :2]
    c_warn, h_warn = shapes.rect(table.warning_depth, owner)
    warn = rect_hits_box(c_warn, u, w, h_warn, half_w, b_lo, b_hi)
    owner, obstacle_row = owner[warn], obstacle_row[warn]
    c_prot, h_prot = shapes.rect(table.protective_depth, owner)
    prot = rect_hits_box(c_prot, u[warn], w[warn], h_prot, half_w[warn], b_lo[warn], b_hi[warn])
    return owner, obstacle_row, prot, np.ones(len(owner), dtype=bool)
