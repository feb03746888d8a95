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
    span = np.floor(aabb_max / cell_size).astype(np.int64) - lo + 1
    any_flat = bool(flat.any())
    if any_flat:
        # A pair with a NORMAL_2D side ignores Z, so those pairs come from a second hash with
        # Z collapsed; pairs of two 3D objects come from the full 3D hash.
        span_xy = span.copy()
        span_xy[:, 2] = 1
        big = np.where(flat[:, None], span_xy, span).max(axis=1) > multi_cell_threshold + 1
    else:
        big = span.max(axis=1) > multi_cell_threshold + 1
    any_big = bool(big.any())
    hashed = ~big & ~flat if any_big or any_flat else None
    pairs = [_hashed_pairs(lo, span, hashed, moved)]
    if any_flat:
        lo_xy = lo.copy()
        lo_xy[:, 2] = 0
        xy = _hashed_pairs(lo_xy, span_xy, ~big, moved)
        pairs.append(xy[flat[xy[:, 0]] | flat[xy[:, 1]]])
    if any_big:
        big_idx = np.flatnonzero(big)
        a = np.repeat(big_idx, n)
        b = np.tile(np.arange(n), len(big_idx))
        keep = (a != b) & (moved[a] | moved[b])
        pairs.append(np.stack([a[keep], b[keep]], axis=1))
    out = np.concatenate(pairs) if len(pairs) > 1 else pairs[0]
    if len(out) == 0:
        return out
    first = np.minimum(out[:, 0], out[:, 1])
    second = np.maximum(out[:, 0], out[:, 1])
    code = np.unique(first * n + second)
    return np.stack([code // n, code % n], axis=1)


def _hashed_pairs(
    lo: np.ndarray, span: np.ndarray, members: np.ndarray | None, moved: np.ndarray
) -> np.ndarray:
    """Pairs among ``members`` (a mask; None = all) sharing a cell, each with a moved object.

    Every object is entered once per cell it overlaps; entries are sorted by cell key, and
    each moved object's entries look up the run of equal keys with ``searchsorted``. Pairs
    come out unordered and possibly repeated (the caller dedupes).
    """
    idx = np.arange(len(lo)) if members is None else np.flatnonzero(members)
    empty = np.empty((0, 2), dtype=np.int64)
    if len(idx) < 2:
        return empty
    s = span[idx]
    counts = s[:, 0] * s[:, 1] * s[:, 2]
    if counts.max() == 1:  # common case: every object inside one cell
        owner, cells = idx, lo[idx]
    else:
        owner = np.repeat(idx, counts)
        # Enumerate each object's cells: local offset k in [0, count) -> (dx, dy, dz).
        starts = np.repeat(np.cumsum(counts) - counts, counts)
        k = np.arange(len(owner)) - starts
        sx, sy = np.repeat(s[:, 0], counts), np.repeat(s[:, 1], counts)
        cells = lo[owner] + np.stack([k % sx, (k // sx) % sy, k // (sx * sy)], axis=1)
    keys = _keys(cells)
    order = np.argsort(keys)
    keys, owner = keys[order], owner[order]
    mine = moved[owner]
    if not mine.any():
        return empty
    probe = keys[mine]
    left = np.searchsorted(keys, probe, "left")
    run = np.searchsorted(keys, probe, "right") - left
    shared = run > 1
    if not shared.any():
        return empty
    probe_owner, left, run = owner[mine][shared], left[shared], run[shared]
    which = np.repeat(np.arange(len(run)), run)
    offset = np.arange(len(which)) - np.repeat(np.cumsum(run) - run, run)
    a = probe_owner[which]
    b = owner[left[which] + offset]
    keep = a != b
    return np.stack([a[keep], b[keep]], axis=1)
