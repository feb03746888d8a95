"""Which obstacles may stand in which safety field: a pair list kept between steps.

The fields' own join, not the collision broad phase: each field (a box around its warning
field and z band) is paired with every obstacle box (other robots' AABBs, other objects', a
map's boxes) that it may touch, and the list is kept from step to step (a Verlet list). When
it is built, every box is grown by :data:`SKIN` on each side and swept over :data:`AHEAD` steps
of its current velocity, and the pairs are those of overlapping grown boxes. While every field
and every moving obstacle box stays inside its grown box, no pair can have begun to overlap
that is not in the list, so the step only tests the listed pairs exactly
(``safety.py``). Boxes that left their grown box are grown again and joined anew against
everything (the few that escaped are hashed, the rest queried against them); when many
escaped, or the fields or the obstacles changed, the list is built anew. A map's boxes do not
move and are never checked.

The join itself is a uniform grid: the target boxes are entered in every cell they cover,
sorted by cell, and each query box looks up the cells it covers (``searchsorted``); a pair
found in several cells is kept in one (the cell of its overlap's lower corner), so no pair is
listed twice and nothing is deduplicated by sorting pairs.
"""

from __future__ import annotations

import numpy as np

__all__ = ["AHEAD", "SKIN", "FieldPairs", "box_pairs"]

SKIN = 0.2  # m every box is grown by on each side when the list is built
AHEAD = 8  # steps of its velocity a grown box also covers
_Z_SKIN = 0.01  # m in z (robots rarely change height)
_MAX_SPAN = 64  # cells a target may span per axis and be hashed (else tested against all)
_REBUILD_SHARE = 4  # escaped boxes beyond 1 / this share of all: build the list anew
_EMPTY = np.zeros(0, dtype=np.int64)


def _cover(c_lo: np.ndarray, c_hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(box index, cell x, cell y) of every cell each box covers, from (K, 2) cell ranges."""
    nx = c_hi[:, 0] - c_lo[:, 0] + 1
    ny = c_hi[:, 1] - c_lo[:, 1] + 1
    count = nx * ny
    if not np.count_nonzero(count - 1):  # every box in one cell
        return np.arange(len(c_lo)), c_lo[:, 0], c_lo[:, 1]
    idx = np.repeat(np.arange(len(c_lo)), count)
    local = np.arange(len(idx)) - np.repeat(np.cumsum(count) - count, count)
    ny_i = ny[idx]
    return idx, c_lo[idx, 0] + local // ny_i, c_lo[idx, 1] + local % ny_i


def _overlap(
    q_lo: np.ndarray,
    q_hi: np.ndarray,
    t_lo: np.ndarray,
    t_hi: np.ndarray,
    qi: np.ndarray,
    ti: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The pairs ``(qi[k], ti[k])`` whose boxes overlap on every axis (touching counts),
    axis by axis, each axis testing only the pairs the previous ones kept."""
    for axis in range(q_lo.shape[1]):
        if not len(qi):
            break
        ql, qh = q_lo[:, axis], q_hi[:, axis]
        tl, th = t_lo[:, axis], t_hi[:, axis]
        ok = (ql[qi] <= th[ti]) & (tl[ti] <= qh[qi])
        if np.count_nonzero(ok) < len(ok):
            qi, ti = qi[ok], ti[ok]
    return qi, ti


def box_pairs(
    q_lo: np.ndarray, q_hi: np.ndarray, t_lo: np.ndarray, t_hi: np.ndarray, cell: float
) -> tuple[np.ndarray, np.ndarray]:
    """(query index, target index) of every pair of overlapping boxes, each pair once.

    Each target is entered in the grid cell of its centre (a counting sort over a dense grid
    of cells spanning the targets); each query visits the cells whose targets could reach it
    (its box grown by the largest target half extent) and tests those exactly.

    Args:
        q_lo, q_hi: (Q, D) query boxes (D >= 2; the grid uses x and y, the test every axis).
        t_lo, t_hi: (T, D) target boxes.
        cell: Grid cell edge (m); coarsened when the targets are spread so thinly that the
            grid would have many more cells than targets.
    """
    if not len(q_lo) or not len(t_lo):
        return _EMPTY, _EMPTY
    big = ~(np.max(t_hi[:, :2] - t_lo[:, :2], axis=1) < _MAX_SPAN * cell)  # NaN, inf: big
    parts_q, parts_t = [], []
    if np.count_nonzero(big):  # huge boxes (a floor): against every query
        b = big.nonzero()[0]
        qi = np.repeat(np.arange(len(q_lo)), len(b))
        ti = np.tile(b, len(q_lo))
        qi, ti = _overlap(q_lo, q_hi, t_lo, t_hi, qi, ti)
        parts_q.append(qi)
        parts_t.append(ti)
    small = (~big).nonzero()[0]
    if len(small):
        qi, ti = _grid_pairs(q_lo, q_hi, t_lo, t_hi, small, cell)
        parts_q.append(qi)
        parts_t.append(ti)
    if len(parts_q) == 1:
        return parts_q[0], parts_t[0]
    return np.concatenate(parts_q), np.concatenate(parts_t)


def _grid_pairs(
    q_lo: np.ndarray,
    q_hi: np.ndarray,
    t_lo: np.ndarray,
    t_hi: np.ndarray,
    small: np.ndarray,
    cell: float,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`box_pairs` for the targets ``small`` (each spanning few cells)."""
    lo, hi = t_lo[small, :2], t_hi[small, :2]
    centre = 0.5 * (lo + hi)
    # A target reaching a query has its centre within the query grown by this (rounding
    # covered by the slack).
    reach = 0.5 * np.max(hi - lo, axis=0) * (1.0 + 1e-9) + 1e-9
    origin = centre.min(axis=0)
    extent = centre.max(axis=0) - origin
    cells_wanted = 4 * len(small) + 1024
    if (extent[0] / cell + 1) * (extent[1] / cell + 1) > cells_wanted:
        cell = max(cell, float(np.sqrt(extent[0] * extent[1] / cells_wanted)) * 1.5)
    inv = 1.0 / cell
    n_x, n_y = int(extent[0] * inv) + 1, int(extent[1] * inv) + 1
    cx = ((centre[:, 0] - origin[0]) * inv).astype(np.int64)
    cy = ((centre[:, 1] - origin[1]) * inv).astype(np.int64)
    key = cx * n_y + cy
    n_cells = n_x * n_y
    # Up to 65,536 cells the keys fit 16 bits, which numpy sorts by radix (linear time).
    order = (key.astype(np.uint16) if n_cells <= 65536 else key).argsort(kind="stable")
    count = np.bincount(key, minlength=n_cells)
    first = np.cumsum(count) - count
    by_cell = small[order]
    # Each query's range of cells, clipped to the grid (outside it: nothing to meet).
    top = np.array([n_x - 1, n_y - 1], dtype=float)
    a = (q_lo[:, :2] - reach - origin) * inv
    b = (q_hi[:, :2] + reach - origin) * inv
    inside = np.all((b >= 0.0) & (a < top + 1.0), axis=1)
    if not np.count_nonzero(inside):
        return _EMPTY, _EMPTY
    qs = inside.nonzero()[0]
    c_lo = np.floor(np.clip(a[qs], 0.0, top)).astype(np.int64)
    c_hi = np.floor(np.clip(b[qs], 0.0, top)).astype(np.int64)
    q_idx, x, y = _cover(c_lo, c_hi)
    k = x * n_y + y
    n = count[k]
    hit = n.nonzero()[0]
    q_idx, k, n = qs[q_idx[hit]], k[hit], n[hit]
    qi = np.repeat(q_idx, n)
    at = np.arange(len(qi)) - np.repeat(np.cumsum(n) - n - first[k], n)
    ti = by_cell[at]
    return _overlap(q_lo, q_hi, t_lo, t_hi, qi, ti)


def _grown(lo: np.ndarray, hi: np.ndarray, shift: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boxes grown by the skin and swept by ``shift`` ((K, 3) m)."""
    skin = np.array([SKIN, SKIN, _Z_SKIN])
    return lo + np.minimum(shift, 0.0) - skin, hi + np.maximum(shift, 0.0) + skin


class FieldPairs:
    """The (field, obstacle) pairs that may touch, kept between steps (see the module doc).

    Obstacles are indexed ``0 .. N-1`` for the moving ones (the caller's object boxes) and
    ``N ..`` for the static boxes that follow them.
    """

    def __init__(self) -> None:
        self.field = _EMPTY  # pair -> field index
        self.obstacle = _EMPTY  # pair -> obstacle index
        self._key: tuple[int, ...] | None = None
        self._fields = np.zeros(0, dtype=np.int64)
        self._rows = np.zeros(0, dtype=np.int64)
        self._gf = (np.zeros((0, 3)), np.zeros((0, 3)))
        self._go = (np.zeros((0, 3)), np.zeros((0, 3)))
        self._cell = 1.0
        self.builds = 0
        """Times the list was built anew (for tests and the benchmark)."""
        self.patches = 0
        """Steps in which some boxes were joined again (for tests and the benchmark)."""

    def invalidate(self) -> None:
        """Build the list anew at the next :meth:`update`."""
        self._key = None

    def update(
        self,
        key: tuple[int, ...],
        field_rows: np.ndarray,
        f_box: tuple[np.ndarray, np.ndarray],
        f_shift: np.ndarray,
        obstacle_rows: np.ndarray,
        o_box: tuple[np.ndarray, np.ndarray],
        o_shift: np.ndarray,
        static: tuple[np.ndarray, np.ndarray],
        own: np.ndarray,
    ) -> None:
        """Bring the pair list up to date with this step's boxes.

        Args:
            key: Changes whenever the static boxes change (their count and a version).
            field_rows: (M,) store rows of the fields' owners.
            f_box: (M, 3) minima and maxima of the fields (warning field, z band).
            f_shift: (M, 3) how far each field moves in :data:`AHEAD` steps (m).
            obstacle_rows: (N,) store rows of the moving obstacles.
            o_box: (N, 3) their minima and maxima.
            o_shift: (N, 3) how far each moves in :data:`AHEAD` steps (m).
            static: (S, 3) minima and maxima of the static boxes.
            own: (M,) each field's owner's index among the obstacles, -1 for none (that pair
                is never listed).
        """
        same = (
            key == self._key
            and np.array_equal(field_rows, self._fields)
            and np.array_equal(obstacle_rows, self._rows)
        )
        if not same:
            self._build(key, field_rows, f_box, f_shift, obstacle_rows, o_box, o_shift, static, own)
            return
        gf_lo, gf_hi = self._gf
        go_lo, go_hi = self._go
        n = len(obstacle_rows)
        # The usual step: everything inside its grown box (whole-array tests, no per-row
        # reduction).
        if (
            np.all(f_box[0] >= gf_lo)
            and np.all(f_box[1] <= gf_hi)
            and np.all(o_box[0] >= go_lo[:n])
            and np.all(o_box[1] <= go_hi[:n])
        ):
            return
        f_out = np.any((f_box[0] < gf_lo) | (f_box[1] > gf_hi), axis=1)
        o_out = np.any((o_box[0] < go_lo[:n]) | (o_box[1] > go_hi[:n]), axis=1)
        nf, no = int(np.count_nonzero(f_out)), int(np.count_nonzero(o_out))
        if _REBUILD_SHARE * (nf + no) > len(field_rows) + n:
            self._build(key, field_rows, f_box, f_shift, obstacle_rows, o_box, o_shift, static, own)
            return
        self._patch(f_out, o_out, f_box, f_shift, o_box, o_shift, own)

    def _build(
        self,
        key: tuple[int, ...],
        field_rows: np.ndarray,
        f_box: tuple[np.ndarray, np.ndarray],
        f_shift: np.ndarray,
        obstacle_rows: np.ndarray,
        o_box: tuple[np.ndarray, np.ndarray],
        o_shift: np.ndarray,
        static: tuple[np.ndarray, np.ndarray],
        own: np.ndarray,
    ) -> None:
        self.builds += 1
        self._key = key
        self._fields = field_rows.copy()
        self._rows = obstacle_rows.copy()
        self._gf = _grown(*f_box, f_shift)
        lo, hi = _grown(*o_box, o_shift)
        self._go = (np.concatenate((lo, static[0])), np.concatenate((hi, static[1])))
        ext = self._gf[1][:, :2] - self._gf[0][:, :2]
        self._cell = max(float(np.median(ext.max(axis=1))), 0.05) if len(ext) else 1.0
        f, o = box_pairs(*self._gf, lo, hi, self._cell)
        if len(static[0]):  # the map's boxes in a grid of their own (their sizes differ)
            fs, os_ = box_pairs(*self._gf, *static, self._cell)
            f, o = np.concatenate((f, fs)), np.concatenate((o, os_ + len(lo)))
        keep = o != own[f]
        self.field, self.obstacle = f[keep], o[keep]

    def _patch(
        self,
        f_out: np.ndarray,
        o_out: np.ndarray,
        f_box: tuple[np.ndarray, np.ndarray],
        f_shift: np.ndarray,
        o_box: tuple[np.ndarray, np.ndarray],
        o_shift: np.ndarray,
        own: np.ndarray,
    ) -> None:
        """Grow the escaped boxes again and join them against everything."""
        self.patches += 1
        gf_lo, gf_hi = self._gf
        go_lo, go_hi = self._go
        fi, oi = f_out.nonzero()[0], o_out.nonzero()[0]
        lo, hi = _grown(f_box[0][fi], f_box[1][fi], f_shift[fi])
        gf_lo[fi], gf_hi[fi] = lo, hi
        lo, hi = _grown(o_box[0][oi], o_box[1][oi], o_shift[oi])
        go_lo[oi], go_hi[oi] = lo, hi
        o_mark = np.zeros(len(go_lo), dtype=bool)
        o_mark[oi] = True
        drop = f_out[self.field] | o_mark[self.obstacle]
        parts_f, parts_o = [self.field[~drop]], [self.obstacle[~drop]]
        if len(fi):  # escaped fields against every obstacle (obstacles queried, fields hashed)
            o, f = box_pairs(go_lo, go_hi, gf_lo[fi], gf_hi[fi], self._cell)
            f = fi[f]
            keep = ~o_mark[o]  # escaped obstacles come below, with every field
            parts_f.append(f[keep])
            parts_o.append(o[keep])
        if len(oi):  # every field against the escaped obstacles
            f, o = box_pairs(gf_lo, gf_hi, go_lo[oi], go_hi[oi], self._cell)
            parts_f.append(f)
            parts_o.append(oi[o])
        f, o = np.concatenate(parts_f), np.concatenate(parts_o)
        keep = o != own[f]
        self.field, self.obstacle = f[keep], o[keep]
