"""The collision check's loops as numba kernels: the AABB refresh of moved rows and the broad
phase's shared-cell pairs (``geometry.CollisionGeometry.refresh``,
``broadphase.candidate_pairs``).

Imported only when numba is used (``base/compiled.py``). :func:`refresh_upright` gives the
numpy code's AABBs (one addition per corner, as there) for moved rows at identity
orientation and leaves anything else to it. :class:`SharedCellPairs` returns exactly the pairs the
numpy code returns for the same input: every object is entered into each cell its AABB
overlaps, two objects pair when they share a cell and one of them moved, and the pairs come
out unique and ascending. The numpy code finds shared cells through a hash table; here the
entries are sorted by cell with a radix sort, whose passes read and write memory in order: a
hash table of 200,000 entries is probed at random and, on this machine, costs several times
more in cache misses than the arithmetic (measured: 8.6 ms to fill and clear one of 187,000
entries, against about 2 ms for the sort).

Cells are numbered densely within the box the objects' cells span (x, y, z bit fields), which
names the same cells as the numpy code's packed keys as long as no axis spans 2**20 cells (past
that the packed keys may alias; the kernel then hands over to the numpy code, as it does when an
object spans more than ``multi_cell_threshold`` cells). Every buffer lives from one call to the
next (:class:`SharedCellPairs`): a fresh 100,000-row temporary costs more in page faults than
the work done in it.

:func:`field_pair_hits` is the safety fields' exact test of their listed pairs
(``safety_geometry.pair_hits``): pair by pair, the very operations of the numpy code in the
same order (numba neither fuses nor reorders floating-point operations unless asked to), so
its answers are the same bit for bit; it stops at the first axis that separates a pair, as
the numpy code tests only the pairs the previous axes kept. :func:`field_speeds` and
:func:`field_frames` lay the fields out for a step (``safety_state.FieldTable.shapes``, the
field columns and the warning fields' bounds) in one pass over the owners instead of some
forty numpy passes, each value by the numpy code's operations in its order
(``tests/core/traffic/test_safety_join.py`` compares them step by step). The fields' grid join
(``safety_join.box_pairs``) has no kernel: a straightforward one (the same grid, one loop per
query and strip of cells) measured no faster than the numpy join at 10,000 robots (0.8-1.1 ms
against 0.9), its time going into random reads of the cells' offsets.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["SharedCellPairs", "field_frames", "field_pair_hits", "field_speeds", "refresh_upright"]

_HAND_OVER = -1  # the kernel's status when the numpy code must run
_DIGIT = 11  # bits sorted per radix pass
_AXIS_BITS = 20  # cells per axis beyond 2**this: hand over (the packed keys may alias)


@numba.njit(cache=True, nogil=True)
def refresh_upright(  # pragma: no cover - compiled; the numpy code is the reference
    position: np.ndarray,
    orientation: np.ndarray,
    offsets: np.ndarray,
    box: np.ndarray,
    aabb: np.ndarray,
    exact: np.ndarray,
    moved: np.ndarray,
    high: int,
) -> int:
    """World AABBs (``aabb``, (2, N, 3)) and ``exact`` flags of the rows below ``high`` flagged
    in ``moved``, all of them at identity orientation; return how many, or -1 as soon as one
    is rotated (the caller then refreshes them all with numpy).

    ``offsets``: (2, N, 3) padded body-frame corners; ``box``: rows that are one box shape.
    """
    count = 0
    for r in range(high):
        if not moved[r]:
            continue
        if (
            orientation[r, 3] != 1.0
            or orientation[r, 0] != 0.0
            or orientation[r, 1] != 0.0
            or orientation[r, 2] != 0.0
        ):
            return -1
        for a in range(3):
            aabb[0, r, a] = position[r, a] + offsets[0, r, a]
            aabb[1, r, a] = position[r, a] + offsets[1, r, a]
        exact[r] = box[r]
        count += 1
    return count


@numba.njit(cache=True, nogil=True)
def _radix(  # pragma: no cover - compiled
    src: np.ndarray, dst: np.ndarray, count: int, shift: int, bits: int, hist: np.ndarray
) -> np.ndarray:
    """Stable LSD sort of ``src[:count]`` by bits ``[shift, shift + bits)``; returns the
    buffer (``src`` or ``dst``) that holds the result."""
    top = (1 << _DIGIT) - 1
    done = 0
    while done < bits:
        sh = shift + done
        done += _DIGIT
        hist[:] = 0
        for e in range(count):
            hist[(src[e] >> sh) & top] += 1
        if hist.max() == count:  # one digit for all: nothing to move
            continue
        total = 0
        for b in range(top + 1):
            c = hist[b]
            hist[b] = total
            total += c
        for e in range(count):
            v = src[e]
            b = (v >> sh) & top
            dst[hist[b]] = v
            hist[b] += 1
        src, dst = dst, src
    return src


@numba.njit(cache=True)
def _bits_for(count: int) -> int:  # pragma: no cover - compiled
    """Bits that number ``count`` values (0 .. count - 1)."""
    bits = 0
    top = count - 1
    while top > 0:
        bits += 1
        top >>= 1
    return bits


@numba.njit(cache=True, nogil=True)
def _kernel(  # pragma: no cover - compiled; the numpy code is the reference
    aabb_min: np.ndarray,
    aabb_max: np.ndarray,
    moved: np.ndarray,
    inv_cell: float,
    threshold: float,
    work: np.ndarray,
) -> tuple[np.ndarray, int]:
    """``(pairs, status)``: status 0, or :data:`_HAND_OVER`, or ``-2 - size`` when ``work``
    needs ``size`` entries (then call again with a larger one)."""
    n = aabb_min.shape[0]
    none = np.empty((0, 2), dtype=np.int64)
    if 6 * n + (1 << _DIGIT) > len(work):
        return none, -2 - (10 * n + (1 << _DIGIT))
    hist = work[: 1 << _DIGIT]
    cells = work[1 << _DIGIT : (1 << _DIGIT) + 6 * n].reshape((n, 6))  # lo x y z, span x y z
    lo_x = lo_y = lo_z = np.int64(1) << 62
    hi_x = hi_y = hi_z = -lo_x
    total = 0
    for i in range(n):
        count = 1
        for a in range(3):
            c0 = np.int64(np.floor(aabb_min[i, a] * inv_cell))
            c1 = np.int64(np.floor(aabb_max[i, a] * inv_cell))
            s = c1 - c0
            if s > threshold:
                return none, _HAND_OVER
            cells[i, a] = c0
            cells[i, 3 + a] = s
            count *= s + 1
        lo_x, hi_x = min(lo_x, cells[i, 0]), max(hi_x, cells[i, 0] + cells[i, 3])
        lo_y, hi_y = min(lo_y, cells[i, 1]), max(hi_y, cells[i, 1] + cells[i, 4])
        lo_z, hi_z = min(lo_z, cells[i, 2]), max(hi_z, cells[i, 2] + cells[i, 5])
        total += count
    limit = np.int64(1) << _AXIS_BITS
    if hi_x - lo_x >= limit or hi_y - lo_y >= limit or hi_z - lo_z >= limit:
        return none, _HAND_OVER
    bz = _bits_for(hi_z - lo_z + 1)
    by = _bits_for(hi_y - lo_y + 1)
    bx = _bits_for(hi_x - lo_x + 1)
    owner_bits = _bits_for(n)
    cell_bits = bx + by + bz
    if cell_bits + owner_bits > 62:
        return none, _HAND_OVER
    base = (1 << _DIGIT) + 6 * n
    if base + 2 * total > len(work):
        return none, -2 - (base + 3 * total)
    entries = work[base : base + total]
    spare = work[base + total : base + 2 * total]
    e = 0
    owner_mask = (np.int64(1) << owner_bits) - 1
    for i in range(n):
        for dx in range(cells[i, 3] + 1):
            x = (cells[i, 0] + dx - lo_x) << (by + bz)
            for dy in range(cells[i, 4] + 1):
                xy = x | ((cells[i, 1] + dy - lo_y) << bz)
                for dz in range(cells[i, 5] + 1):
                    entries[e] = ((xy | (cells[i, 2] + dz - lo_z)) << owner_bits) | i
                    e += 1
    entries = _radix(entries, spare, total, owner_bits, cell_bits, hist)
    # Pairs of owners within each run of one cell (owners ascend in a run: stable sort).
    pairs = 0
    run = 0
    for e in range(1, total + 1):
        if e < total and (entries[e] >> owner_bits) == (entries[run] >> owner_bits):
            continue
        m = e - run
        pairs += m * (m - 1) // 2
        run = e
    codes_at = base + 2 * total
    if codes_at + 2 * pairs > len(work):
        return none, -2 - (codes_at + 3 * pairs)
    codes = work[codes_at : codes_at + pairs]
    k = 0
    run = 0
    for e in range(1, total + 1):
        if e < total and (entries[e] >> owner_bits) == (entries[run] >> owner_bits):
            continue
        for a in range(run, e):
            i = entries[a] & owner_mask
            for b in range(a + 1, e):
                j = entries[b] & owner_mask
                if moved[i] or moved[j]:
                    codes[k] = (i << owner_bits) | j
                    k += 1
        run = e
    codes = _radix(codes, work[codes_at + pairs : codes_at + 2 * pairs], k, 0, 2 * owner_bits, hist)
    out = np.empty((k, 2), dtype=np.int64)
    m = 0
    for a in range(k):
        if a and codes[a] == codes[a - 1]:
            continue
        out[m, 0] = codes[a] >> owner_bits
        out[m, 1] = codes[a] & owner_mask
        m += 1
    return out[:m], 0


class SharedCellPairs:
    """Callable as ``(aabb_min, aabb_max, moved, inv_cell, threshold) -> (pairs, done)``:
    ``pairs`` (K, 2) int64 as ``broadphase.candidate_pairs`` finds them, ``done`` False when
    the numpy code must run (an object spans more than ``threshold`` cells, or the cells span
    more than 2**20 along an axis). Keeps its buffer between calls; one per collision system."""

    def __init__(self) -> None:
        self._work = np.empty(1 << 14, dtype=np.int64)

    def __call__(
        self,
        aabb_min: np.ndarray,
        aabb_max: np.ndarray,
        moved: np.ndarray,
        inv_cell: float,
        threshold: float,
    ) -> tuple[np.ndarray, bool]:
        while True:
            pairs, status = _kernel(aabb_min, aabb_max, moved, inv_cell, threshold, self._work)
            if status == 0:
                return pairs, True
            if status == _HAND_OVER:
                return pairs, False
            self._work = np.empty(-2 - status, dtype=np.int64)


# Rows of ``safety_geometry.field_columns`` and ``box_columns`` (if they drift apart, the
# test against the numpy code fails).
_CW, _CP = 0, 5
_UX, _UY, _WX, _WY, _HW, _AUX, _AUY, _AWX, _AWY, _ZLO, _ZHI = range(10, 21)
_MX, _MY, _HX, _HY, _BZLO, _BZHI = range(6)


@numba.njit(cache=True, nogil=True, inline="always")
def _sat(f: np.ndarray, b: np.ndarray, at: int, i: int, j: int) -> bool:  # pragma: no cover
    """``safety_geometry._sat`` for field ``i`` and box ``j`` (the same operations)."""
    hx, hy = b[_HX, j], b[_HY, j]
    dx = f[at, i] - b[_MX, j]
    dy = f[at + 1, i] - b[_MY, j]
    if not (abs(dx) <= f[at + 3, i] + hx):
        return False
    if not (abs(dy) <= f[at + 4, i] + hy):
        return False
    along = dx * f[_UX, i] + dy * f[_UY, i]
    reach = f[at + 2, i] + hx * f[_AUX, i] + hy * f[_AUY, i]
    if not (abs(along) <= reach):
        return False
    across = dx * f[_WX, i] + dy * f[_WY, i]
    reach = f[_HW, i] + hx * f[_AWX, i] + hy * f[_AWY, i]
    return abs(across) <= reach


@numba.njit(cache=True, nogil=True)
def field_pair_hits(  # pragma: no cover - compiled; the numpy code is the reference
    fields: np.ndarray, boxes: np.ndarray, field: np.ndarray, box: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``safety_geometry.pair_hits``: (indices of the pairs in the warning field and the z
    band, whether each is in the protective field too)."""
    n = len(field)
    hit = np.empty(n, dtype=np.int64)
    prot = np.empty(n, dtype=np.bool_)
    k = 0
    for p in range(n):
        i, j = field[p], box[p]
        if not (boxes[_BZHI, j] >= fields[_ZLO, i] and boxes[_BZLO, j] <= fields[_ZHI, i]):
            continue
        if not _sat(fields, boxes, _CW, i, j):
            continue
        hit[k] = p
        prot[k] = _sat(fields, boxes, _CP, i, j)
        k += 1
    return hit[:k], prot[:k]


@numba.njit(cache=True, nogil=True)
def field_speeds(  # pragma: no cover - compiled; the numpy code is the reference
    rows: np.ndarray, velocity: np.ndarray, moving_eps: float, speed: np.ndarray
) -> int:
    """Ground speeds (``speed``) of the field owners' store ``rows``; return how many stand
    (slower than ``moving_eps``): ``safety_state.FieldTable.shapes``' first pass."""
    standing = 0
    for i in range(len(rows)):
        r = rows[i]
        speed[i] = np.hypot(velocity[r, 0], velocity[r, 1])
        if not speed[i] > moving_eps:
            standing += 1
    return standing


@numba.njit(cache=True, nogil=True)
def field_frames(  # pragma: no cover - compiled; the numpy code is the reference
    rows: np.ndarray,
    store: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    seg: np.ndarray,
    state: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    params: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    limits: tuple[float, float],
    speed: np.ndarray,
    out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """The rest of ``FieldTable.shapes``, ``z_band``, ``FieldShapes.bounds`` and
    ``safety_geometry.field_columns`` in one pass over the field owners, each value by the
    numpy code's operations in their order.

    ``store``: the store's (velocity, orientation, position, on_path by row); ``seg``: the
    (capacity, 2) directions of the segments about to be driven (read only for standing
    owners); ``state``: (held, held_dir, held_speed, last_scale); ``params``: (decel,
    margin_p, margin_w, half, side, z_off); ``limits``: (moving speed, clearance); ``speed``:
    from :func:`field_speeds`. ``out``: (shape (8, M): cx, cy, ux, uy, wx, wy, ext_u, half_w;
    depths (3, M): the planned speed, protective and warning depths; active (M,); fields
    (21, M); lo and hi (M, 3): the warning fields' bounds with their z band)."""
    velocity, orientation, position, on_path = store
    held, held_dir, held_speed, last_scale = state
    decel, margin_p, margin_w, half, side, z_off = params
    moving_eps, clearance = limits
    shape, depths, active, fields, lo, hi = out
    for i in range(len(rows)):
        r = rows[i]
        v = speed[i]
        moving = v > moving_eps
        has_seg = False
        sx = sy = 0.0
        if not moving:
            sx, sy = seg[r, 0], seg[r, 1]
            has_seg = sx != 0.0 or sy != 0.0
        active[i] = on_path[r] and (moving or held[i] or has_seg)
        if moving:
            tx, ty = velocity[r, 0] / v, velocity[r, 1] / v
        elif has_seg:
            tx, ty = sx, sy
        elif held[i]:
            tx, ty = held_dir[i, 0], held_dir[i, 1]
        else:
            tx, ty = 1.0, 0.0
        last = last_scale[i]
        depths[0, i] = held_speed[i] if held[i] else v / (last if last > 0 else 1.0)
        prot = v * v / (2.0 * decel[i]) + margin_p[i]
        warn = prot + margin_w[i]
        depths[1, i], depths[2, i] = prot, warn
        # heading_columns
        qx, qy, qz, qw = orientation[r, 0], orientation[r, 1], orientation[r, 2], orientation[r, 3]
        hx = 1.0 - 2.0 * (qy * qy + qz * qz)
        hy = 2.0 * (qw * qz + qx * qy)
        norm = np.hypot(hx, hy)
        if norm < 1e-12:
            norm = 1.0
        hx, hy = hx / norm, hy / norm
        # FieldShapes
        cx, cy = position[r, 0], position[r, 1]
        wx, wy = -ty, tx
        cos = abs(tx * hx + ty * hy)
        sin = abs(tx * hy - ty * hx)
        ext_u = half[i, 0] * cos + half[i, 1] * sin
        half_w = half[i, 0] * sin + half[i, 1] * cos + side[i]
        shape[0, i], shape[1, i], shape[2, i], shape[3, i] = cx, cy, tx, ty
        shape[4, i], shape[5, i], shape[6, i], shape[7, i] = wx, wy, ext_u, half_w
        # z_band
        z = position[r, 2]
        z_lo = z + z_off[i, 0] + clearance
        z_hi = z + z_off[i, 1]
        # field_columns, and bounds of the warning field (the same terms)
        aux, auy, awx, awy = abs(tx), abs(ty), abs(wx), abs(wy)
        for at, depth in ((_CW, warn), (_CP, prot)):
            h = 0.5 * depth
            reach = ext_u + h
            fields[at, i] = cx + tx * reach
            fields[at + 1, i] = cy + ty * reach
            fields[at + 2, i] = h
            fields[at + 3, i] = aux * h + awx * half_w
            fields[at + 4, i] = auy * h + awy * half_w
        x, y = fields[_CW, i], fields[_CW + 1, i]
        rx, ry = fields[_CW + 3, i], fields[_CW + 4, i]
        lo[i, 0], lo[i, 1], lo[i, 2] = x - rx, y - ry, z_lo
        hi[i, 0], hi[i, 1], hi[i, 2] = x + rx, y + ry, z_hi
        fields[_UX, i], fields[_UY, i], fields[_WX, i], fields[_WY, i] = tx, ty, wx, wy
        fields[_HW, i], fields[_AUX, i], fields[_AUY, i] = half_w, aux, auy
        fields[_AWX, i], fields[_AWY, i] = awx, awy
        fields[_ZLO, i], fields[_ZHI, i] = z_lo, z_hi
