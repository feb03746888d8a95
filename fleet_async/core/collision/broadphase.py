"""Broad-phase collision culling on arrays: a vectorised spatial hash without a sort.

Every object is entered into each grid cell its AABB overlaps; two objects are candidates when
they share a cell. Finding the shared cells does not sort the N entries: each entry's cell key
is hashed to a slot of a table about twice the number of entries, every entry writes its index
into its slot, and an entry that reads back another's index shares its slot with it. Only the
few entries in shared slots (a slot collision of two different cells is harmless: equal keys
decide) are sorted and paired. The work is O(N) numpy passes, so 100,000 objects cost about
ten times 10,000.

Objects much larger than a cell (more than ``multi_cell_threshold`` cells along an axis) would
flood the hash, so they are kept aside and tested against every object by AABB instead.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["aabb_overlap", "auto_cell_size", "candidate_pairs"]

# Cell coordinates are packed into one int64 key, 21 bits per axis (see ``_entries``).
_BITS = 21
_WEIGHTS = np.array([1 << (2 * _BITS), 1 << _BITS, 1], dtype=np.int64)
# Fibonacci hashing: multiply by 2**64 / golden ratio, keep the top bits.
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_EMPTY = np.empty((0, 2), dtype=np.int64)
_NEXT = np.array([0, 1])  # an entry and the next one
# Up to this many entries a sort finds equal keys faster than the hash table (measured).
_SORT_MAX = 6000
# Up to this many objects, entering each in its 1-8 cells in one go (_corner_entries) beats
# adding the further cells axis by axis (_entries): measured 31 vs 41 us at 100 objects, even
# at 500, slower from 1,000 (69 vs 64 us; 1.2 vs 0.9 ms at 10,000).
_CORNER_MAX = 400
# Up to this many moved objects, each is compared with every AABB (_few_movers_pairs) rather
# than hashing all objects' cells: about 5 ns per object per mover against about 100 ns per
# object for the hash.
_FEW_MOVERS = 8
_FEW_MIN_ROWS = 512  # below, the hash's fixed cost is small and it was measured faster
_SLACK = 1e-6  # m: AABBs this close still pair (rounding must never lose a touching pair)


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
    flat: np.ndarray | None,
    moved: np.ndarray,
    cell_size: float,
    multi_cell_threshold: float,
    bounds: np.ndarray | None = None,
    kernel: Callable[..., Any] | None = None,
) -> np.ndarray:
    """Index pairs (i < j) whose AABBs share a hash cell and where i or j moved.

    Args:
        aabb_min: (N, 3) AABB minima of the objects taking part.
        aabb_max: (N, 3) AABB maxima.
        flat: (N,) bool, or None for none; NORMAL_2D objects: any pair with one of them
            ignores Z.
        moved: (N,) bool; pairs where neither moved are left out.
        cell_size: Edge of a hash cell, metres.
        multi_cell_threshold: Objects spanning more cells than this along an axis are
            tested against everything instead of being hashed.
        bounds: (2, N, 3) minima and maxima in one array, when the caller holds them so
            (``aabb_min`` / ``aabb_max`` are then its halves): one numpy call floors both.
        kernel: ``check_jit.SharedCellPairs`` to find the same pairs in one compiled
            call (used when no object is NORMAL_2D and none spans more than the threshold).

    Returns:
        (K, 2) int64 array of unique pairs in ascending order, ``i < j`` in each.
    """
    n = len(aabb_min)
    n_moved = np.count_nonzero(moved) if n >= 2 else 0
    if not n_moved:
        return _EMPTY
    if n_moved <= _FEW_MOVERS and n >= _FEW_MIN_ROWS and bounds is not None:
        return _few_movers_pairs(aabb_min, aabb_max, flat, moved.nonzero()[0], n)
    inv = 1.0 / cell_size
    if kernel is not None and flat is None:
        pairs, done = kernel(aabb_min, aabb_max, moved, inv, float(multi_cell_threshold))
        if done:
            return pairs
    if bounds is not None:
        cells = np.floor(bounds * inv).astype(np.int64)
        lo = cells[0]
        span = cells[1] - lo  # cells spanned - 1, per axis
    else:
        lo = np.floor(aabb_min * inv).astype(np.int64)
        span = np.floor(aabb_max * inv).astype(np.int64) - lo
    if flat is None:
        top = int(span.max())
        if top == 0:  # the common case: every object in one cell
            return _sorted_unique(_shared_cell_pairs(lo @ _WEIGHTS, None, moved), n, False)
        if top == 1 and n <= _CORNER_MAX and multi_cell_threshold >= 1:
            # Small objects, some across a cell edge, none big enough to test against all.
            return _sorted_unique(_shared_cell_pairs(*_corner_entries(lo, span), moved), n, True)
        any_big = top > multi_cell_threshold
        big = _max3(span) > multi_cell_threshold if any_big else np.zeros(n, dtype=bool)
    else:
        # A pair with a NORMAL_2D side ignores Z, so those pairs come from a second hash with
        # Z collapsed; pairs of two 3D objects come from the full 3D hash.
        span_xy = span.copy()
        span_xy[:, 2] = 0
        big = _max3(np.where(flat[:, None], span_xy, span)) > multi_cell_threshold
        any_big = bool(np.count_nonzero(big))
    hashed = ~big & ~flat if flat is not None else (~big if any_big else None)
    pairs = [_shared_cell_pairs(*_entries(lo, span, hashed), moved)]
    if flat is not None:
        lo_xy = lo.copy()
        lo_xy[:, 2] = 0
        xy = _shared_cell_pairs(*_entries(lo_xy, span_xy, ~big), moved)
        pairs.append(xy[flat[xy[:, 0]] | flat[xy[:, 1]]])
    if any_big:
        big_idx = big.nonzero()[0]
        a = np.repeat(big_idx, n)
        b = np.tile(np.arange(n), len(big_idx))
        keep = (a != b) & (moved[a] | moved[b])
        pairs.append(_pairs(a[keep], b[keep]))
    out = np.concatenate(pairs) if len(pairs) > 1 else pairs[0]
    return _sorted_unique(out, n, True)


def _few_movers_pairs(
    aabb_min: np.ndarray,
    aabb_max: np.ndarray,
    flat: np.ndarray | None,
    movers: np.ndarray,
    n: int,
) -> np.ndarray:
    """Pairs of each of a few moved objects with every object whose AABB comes within
    :data:`_SLACK` of its own (Z ignored where a NORMAL_2D side is).

    Not the hash's candidates but a set that holds every pair the narrow phase can find
    touching among them (padded AABBs apart means apart by more than the margin), so the
    check's outcome is the same; it costs a few compares per object and moved object instead
    of hashing every object's cells, which re-hashed 10,000 unmoved rows for one that moved.
    """
    parts = []
    lo_x, hi_x = aabb_min[:, 0], aabb_max[:, 0]
    for i in movers.tolist():
        ax, ay, az = (aabb_min[i] - _SLACK).tolist()
        bx, by, bz = (aabb_max[i] + _SLACK).tolist()
        # x over every row (two 1-D tests: cheaper than a reduction over rows of three), then
        # y and z over the few rows left.
        hit = ((lo_x <= bx) & (hi_x >= ax)).nonzero()[0]
        lo, hi = aabb_min[hit], aabb_max[hit]
        z = (lo[:, 2] <= bz) & (hi[:, 2] >= az)
        if flat is not None:
            z |= flat[hit] | flat[i]
        hit = hit[(lo[:, 1] <= by) & (hi[:, 1] >= ay) & z]
        hit = hit[hit != i]
        parts.append(_pairs(np.full(len(hit), i, dtype=np.int64), hit))
    out = np.concatenate(parts) if len(parts) > 1 else parts[0]
    return _sorted_unique(out, n, True)


def _sorted_unique(pairs: np.ndarray, n: int, may_repeat: bool) -> np.ndarray:
    """Pairs as (min, max), in ascending order, repeats dropped when there may be some."""
    if len(pairs) <= 16:  # a few pairs: plain Python is quicker than eight numpy calls
        if len(pairs) == 0:
            return _EMPTY
        out = sorted({(a, b) if a < b else (b, a) for a, b in pairs.tolist()})
        return np.array(out, dtype=np.int64)
    first = np.minimum(pairs[:, 0], pairs[:, 1])
    second = np.maximum(pairs[:, 0], pairs[:, 1])
    code = np.sort(first * n + second)
    if may_repeat and len(code) > 1:
        code = code[np.concatenate(([True], code[1:] != code[:-1]))]
    return _pairs(code // n, code % n)


def _pairs(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(K, 2) int64 array of the pairs (a[k], b[k]) (cheaper than ``np.stack``)."""
    out = np.empty((len(a), 2), dtype=np.int64)
    out[:, 0] = a
    out[:, 1] = b
    return out


def _max3(a: np.ndarray) -> np.ndarray:
    """Row-wise maximum of an (N, 3) array (faster than ``max(axis=1)`` on narrow rows)."""
    return np.maximum(np.maximum(a[:, 0], a[:, 1]), a[:, 2])


def _entries(
    lo: np.ndarray, span: np.ndarray, members: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray | None]:
    """(cell key, owner) of every hash entry: one per cell each member overlaps.

    Keys are ``x * 2**42 + y * 2**21 + z`` of the cell coordinates, distinct for coordinates
    within +-2**20 cells (farther cells may share keys: extra candidates, which the AABB test
    drops). ``members`` None means all objects; ``owner`` None means entry i is object i.
    """
    idx = None if members is None else members.nonzero()[0]
    if idx is None:
        keys, s, owner = lo @ _WEIGHTS, span, None
    else:
        keys, s, owner = lo[idx] @ _WEIGHTS, span[idx], idx
    if not np.count_nonzero(s):
        return keys, owner
    # Add the further cells axis by axis: along x, every entry so far (offset 0 on x) gets
    # one more entry per extra cell its object spans on x; then y over all of those; then z.
    which = None
    for axis in range(3):
        if not np.count_nonzero(s[:, axis]):
            continue  # no object spans two cells along this axis
        if which is None:
            which = np.arange(len(keys))
        col = s[which, axis]
        top = int(col.max())
        parts_k, parts_w = [keys], [which]
        for k in range(1, top + 1):
            extra = (col >= k).nonzero()[0]
            parts_k.append(keys[extra] + k * _WEIGHTS[axis])
            parts_w.append(which[extra])
        keys, which = np.concatenate(parts_k), np.concatenate(parts_w)
    assert which is not None
    return keys, (which if owner is None else owner[which])


# The 8 cells of a 2 x 2 x 2 block as offsets (x, y, z), their key offsets, and for each way an
# object can span such a block (code 4 * span_x + 2 * span_y + span_z) the cells it covers.
_CORNERS = np.array([(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.int64)
_CORNER_KEYS = _CORNERS @ _WEIGHTS
_SPAN_CODE = np.array([4, 2, 1], dtype=np.int64)
_COVERS = np.logical_and.reduce(
    _CORNERS[None, :, :] <= _CORNERS[:, None, :], axis=2
)  # [code, corner]


def _corner_entries(lo: np.ndarray, span: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(cell key, owner) of every hash entry when no object spans more than two cells along
    an axis: the same entries as :func:`_entries`, in a fixed number of calls."""
    owner, corner = _COVERS.take(span @ _SPAN_CODE, axis=0).nonzero()
    return (lo @ _WEIGHTS)[owner] + _CORNER_KEYS[corner], owner


def _shared_cell_pairs(keys: np.ndarray, owner: np.ndarray | None, moved: np.ndarray) -> np.ndarray:
    """Pairs of entries with equal keys (as owners), each with a moved owner.

    ``owner`` None means entry i is object i. Pairs come out unordered and, for objects that
    share several cells, repeated (the caller dedupes).
    """
    if len(keys) < 2:
        return _EMPTY
    if len(keys) <= _SORT_MAX:
        entries = keys.argsort(kind="stable")
    else:
        shared = _in_shared_slots(keys)
        if len(shared) < 2:
            return _EMPTY
        entries = shared[keys[shared].argsort(kind="stable")]
    k_sorted = keys[entries]
    same = k_sorted[1:] == k_sorted[:-1]
    if not np.count_nonzero(same):
        return _EMPTY
    first = same.nonzero()[0]
    if not np.count_nonzero(same[1:] & same[:-1]):
        # No cell holds three or more: neighbours pair up.
        at = first[:, None] + _NEXT
    else:
        # Pair every entry with each later entry of its run of equal keys.
        m = len(entries)
        boundary = np.concatenate(([True], ~same, [True])).nonzero()[0]
        after = np.repeat(boundary[1:], np.diff(boundary)) - np.arange(m) - 1
        first = np.repeat(np.arange(m), after)
        offset = np.arange(len(first)) - np.repeat(np.cumsum(after) - after, after) + 1
        at = np.empty((len(first), 2), dtype=np.intp)
        at[:, 0] = first
        at[:, 1] = first + offset
    # (K, 2) positions in the sorted entries -> owners. An object's cells are distinct, so the
    # two owners of a pair are never the same object.
    pairs = entries[at] if owner is None else owner[entries[at]]
    flags = moved[pairs]
    return pairs.compress(flags[:, 0] | flags[:, 1], axis=0)  # cheaper than pairs[mask]


def _in_shared_slots(keys: np.ndarray) -> np.ndarray:
    """Entry indices (ascending) whose key equals another entry's key.

    Every entry writes its index into the slot its key hashes to, in a table of at least four
    slots per entry; an entry that reads back another's index lost its slot. A loser with the
    winner's key shares a cell with it; losers with other keys (different cells hashed to one
    slot) are resolved the same way among themselves, with a fresh table.
    """
    found: list[np.ndarray] = []
    entry = np.arange(len(keys))
    while len(entry) > 1:
        e = len(entry)
        bits = max(int(4 * e - 1).bit_length(), 4)
        slot = ((keys.view(np.uint64) * _GOLDEN) >> np.uint64(64 - bits)).astype(np.intp)
        table = np.empty(1 << bits, dtype=np.int32)
        local = np.arange(e, dtype=np.int32)
        table[slot] = local  # one writer of each slot wins; which one does not matter
        winner = table[slot]
        lost = (winner != local).nonzero()[0]
        if not len(lost):
            break
        beaten_by = winner[lost]
        same = keys[lost] == keys[beaten_by]
        if np.count_nonzero(same):
            found += [entry[lost[same]], entry[beaten_by[same]]]
        rest = lost[~same]
        entry, keys = entry[rest], keys[rest]
    if not found:
        return _EMPTY[:, 0]
    return _sorted_set(found)


def _sorted_set(parts: list[np.ndarray]) -> np.ndarray:
    """Ascending distinct values of the arrays in ``parts`` (small arrays)."""
    values = np.sort(np.concatenate(parts))
    if len(values) > 1:
        values = values[np.concatenate(([True], values[1:] != values[:-1]))]
    return values
