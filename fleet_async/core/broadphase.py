"""Broad-phase collision culling on arrays: a vectorised spatial hash.

Every object is inserted into each grid cell its AABB overlaps; two objects are candidates
when they share a cell. Objects much larger than a cell (more than ``multi_cell_threshold``
cells along an axis) would flood the hash, so they are kept aside and tested against every
object by AABB instead. No Python loop runs over objects: the loops below run over the size
of the largest cell, which is small for any sensible cell size.
"""

from __future__ import annotations

import numpy as np

__all__ = ["aabb_overlap", "auto_cell_size", "candidate_pairs"]

# Cell coordinates are packed into one int64 key: 21 bits per axis, offset to be non-negative.
_BITS = 21
_OFFSET = 1 << (_BITS - 1)
_MASK = (1 << _BITS) - 1


def auto_cell_size(aabb_min: np.ndarray, aabb_max: np.ndarray) -> float:
    """A cell size from object sizes: three times the median largest AABB extent (1.0 if none).

    Measured on 10,000 boxes 1 m apart: 2x gives ~3.4 cell entries per object, 3x ~2, and 8x
    crowds cells; 3x was the fastest of 2x / 3x / 4x / 8x.
    """
    if len(aabb_min) == 0:
        return 1.0
    extent = np.max(aabb_max - aabb_min, axis=1)
    size = 3.0 * float(np.median(extent))
    return size if size > 1e-9 else 1.0


def _keys(cells: np.ndarray) -> np.ndarray:
    c = (cells.astype(np.int64) + _OFFSET) & _MASK
    return (c[:, 0] << (2 * _BITS)) | (c[:, 1] << _BITS) | c[:, 2]


def aabb_overlap(
    amin: np.ndarray, amax: np.ndarray, bmin: np.ndarray, bmax: np.ndarray, ignore_z: np.ndarray
) -> np.ndarray:
    """Row-wise AABB overlap (touching counts); Z is skipped where ``ignore_z`` is set."""
    sep = (amin > bmax) | (bmin > amax)
    sep[:, 2] &= ~ignore_z
    return np.logical_not(sep.any(axis=1))


def candidate_pairs(
    aabb_min: np.ndarray,
    aabb_max: np.ndarray,
    flat: np.ndarray,
    moved: np.ndarray,
    cell_size: float,
    multi_cell_threshold: float,
) -> np.ndarray:
    """Index pairs (i < j) whose AABBs share a hash cell and where i or j moved.

    Args:
        aabb_min: (N, 3) AABB minima of the objects taking part.
        aabb_max: (N, 3) AABB maxima.
        flat: (N,) bool; NORMAL_2D objects: any pair with one of them ignores Z.
        moved: (N,) bool; pairs where neither moved are left out.
        cell_size: Edge of a hash cell, metres.
        multi_cell_threshold: Objects spanning more cells than this along an axis are
            tested against everything instead of being hashed.

    Returns:
        (K, 2) int64 array of unique pairs, rows sorted, ``i < j`` in each.
    """
    n = len(aabb_min)
    if n < 2 or not moved.any():
        return np.empty((0, 2), dtype=np.int64)
    lo = np.floor(aabb_min / cell_size).astype(np.int64)
    hi = np.floor(aabb_max / cell_size).astype(np.int64)
    span = hi - lo + 1
    # A pair with a NORMAL_2D side ignores Z, so those pairs are found in a second hash with
    # Z collapsed; pairs of two 3D objects come from the full 3D hash.
    span_xy = span.copy()
    span_xy[:, 2] = 1
    big = np.where(flat[:, None], span_xy, span).max(axis=1) > multi_cell_threshold + 1
    small = ~big
    pairs = [_hashed_pairs(lo, span, np.flatnonzero(small & ~flat))]
    if flat.any():
        lo_xy = lo.copy()
        lo_xy[:, 2] = 0
        xy = _hashed_pairs(lo_xy, span_xy, np.flatnonzero(small))
        pairs.append(xy[flat[xy[:, 0]] | flat[xy[:, 1]]])
    big_idx = np.flatnonzero(big)
    if len(big_idx):
        others = np.arange(n)
        a = np.repeat(big_idx, n)
        b = np.tile(others, len(big_idx))
        keep = a != b
        pairs.append(np.stack([a[keep], b[keep]], axis=1))
    out = np.concatenate(pairs)
    if len(out) == 0:
        return out
    out.sort(axis=1)
    out = out[moved[out[:, 0]] | moved[out[:, 1]]]
    if len(out) == 0:
        return out
    return np.unique(out, axis=0)


def _hashed_pairs(lo: np.ndarray, span: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Pairs among ``idx`` that share at least one cell."""
    if len(idx) < 2:
        return np.empty((0, 2), dtype=np.int64)
    s = span[idx]
    counts = s.prod(axis=1)
    if (counts == 1).all():  # common case: every object inside one cell
        owner, cells = idx, lo[idx]
    else:
        owner = np.repeat(idx, counts)
        # Enumerate each object's cells: local offset k in [0, count) -> (dx, dy, dz).
        starts = np.repeat(np.cumsum(counts) - counts, counts)
        k = np.arange(len(owner)) - starts
        sx, sy = np.repeat(s[:, 0], counts), np.repeat(s[:, 1], counts)
        dx = k % sx
        dy = (k // sx) % sy
        dz = k // (sx * sy)
        cells = lo[owner] + np.stack([dx, dy, dz], axis=1)
    keys = _keys(cells)
    order = np.argsort(keys, kind="stable")
    keys, owner = keys[order], owner[order]
    found = []
    gap = 1
    while gap < len(keys):
        same = keys[gap:] == keys[:-gap]
        if not same.any():
            break  # sorted keys: no run is longer than `gap`
        found.append(np.stack([owner[:-gap][same], owner[gap:][same]], axis=1))
        gap += 1
    if not found:
        return np.empty((0, 2), dtype=np.int64)
    return np.concatenate(found)
