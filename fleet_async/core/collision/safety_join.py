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

The join itself is a dense uniform grid: each target box is entered in the cell of its
centre (a counting sort; 16-bit keys are radix-sorted), and each query visits the cells whose
targets can reach it (its box grown by the largest target half extent); no pair is found
twice and no pair is sorted. Cells are numbered along the axis the queries are longer on
first, so what a query visits in one strip of cells is one run of the sorted targets: a
lookup per strip, not per cell, which lets the cells be small (a quarter of a typical field)
and the candidates few. The passes work on 1-D columns of the boxes, and the candidates'
x and y bounds are compared as rows of four in one operation (``take``): numpy's passes
over a column of an (N, 3) array, or along its axis 0, are several times slower.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["AHEAD", "SKIN", "FieldPairs", "box_pairs"]

SKIN = 0.2  # m every box is grown by on each side when the list is built
AHEAD = 8  # steps of its velocity a grown box also covers
_Z_SKIN = 0.01  # m in z (robots rarely change height)
_MAX_SPAN = 64  # cells a target may span per axis and be hashed (else tested against all)
_REBUILD_SHARE = 4  # escaped boxes beyond 1 / this share of all: build the list anew
_CELL_SHARE = 0.25  # grid cell edge per ``cell`` (runs make small cells cheap to visit)
_CELLS_PER_TARGET = 8  # the grid has at most about this many cells per target
_EMPTY = np.zeros(0, dtype=np.int64)


def _columns(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(D, K) contiguous columns of (K, D) boxes: numpy's passes over one contiguous column
    are several times faster than over a column of a (K, D) array or along its axis 0."""
    return np.ascontiguousarray(lo.T), np.ascontiguousarray(hi.T)


def _overlap(
    q: tuple[np.ndarray, np.ndarray],
    t: tuple[np.ndarray, np.ndarray],
    qi: np.ndarray,
    ti: np.ndarray,
    axes: range,
) -> tuple[np.ndarray, np.ndarray]:
    """The pairs ``(qi[k], ti[k])`` whose boxes (columns) overlap on ``axes`` (touching
    counts), axis by axis, each axis testing only the pairs the previous ones kept."""
    for axis in axes:
        if not len(qi):
            break
        ok = (q[0][axis][qi] <= t[1][axis][ti]) & (t[0][axis][ti] <= q[1][axis][qi])
        if np.count_nonzero(ok) < len(ok):
            qi, ti = qi[ok], ti[ok]
    return qi, ti


def _overlap_xy(
    q: tuple[np.ndarray, np.ndarray],
    t: tuple[np.ndarray, np.ndarray],
    qi: np.ndarray,
    ti: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_overlap` on x and y in one comparison: each box's four bounds side by side
    (``q_lo <= t_hi`` and ``-q_hi <= -t_lo``), gathered as rows (``take``) and compared at
    once, the four answers read as one 32-bit word."""
    qb = np.empty((len(q[0][0]), 4))
    qb[:, 0], qb[:, 1] = q[0][0], q[0][1]
    np.negative(q[1][0], out=qb[:, 2])
    np.negative(q[1][1], out=qb[:, 3])
    tb = np.empty((len(t[0][0]), 4))
    tb[:, 0], tb[:, 1] = t[1][0], t[1][1]
    np.negative(t[0][0], out=tb[:, 2])
    np.negative(t[0][1], out=tb[:, 3])
    ok = (qb.take(qi, axis=0) <= tb.take(ti, axis=0)).view(np.uint32).ravel() == 0x01010101
    return qi[ok], ti[ok]


def box_pairs(
    q_lo: np.ndarray, q_hi: np.ndarray, t_lo: np.ndarray, t_hi: np.ndarray, cell: float
) -> tuple[np.ndarray, np.ndarray]:
    """(query index, target index) of every pair of overlapping boxes, each pair once.

    Each target is entered in the grid cell of its centre (a counting sort over a dense grid
    of cells spanning the targets); each query visits the cells whose targets could reach it
    (its box grown by the largest target half extent) and tests those exactly. The cells
    are numbered along one axis first, so the cells a query visits in one strip of the other
    axis are one run of the sorted targets: a query costs one lookup per strip, not per cell.

    Args:
        q_lo, q_hi: (Q, D) query boxes (D >= 2; the grid uses x and y, the test every axis).
        t_lo, t_hi: (T, D) target boxes.
        cell: A typical query's size (m); grid cells are a quarter of it, coarsened when the
            targets are spread so thinly that the grid would have many more cells than
            targets.
    """
    if not len(q_lo) or not len(t_lo):
        return _EMPTY, _EMPTY
    q, t = _columns(q_lo, q_hi), _columns(t_lo, t_hi)
    span = np.maximum(t[1][0] - t[0][0], t[1][1] - t[0][1])
    big = ~(span < _MAX_SPAN * cell)  # NaN, inf: big
    parts_q, parts_t = [], []
    if np.count_nonzero(big):  # huge boxes (a floor): against every query
        b = big.nonzero()[0]
        qi = np.repeat(np.arange(len(q_lo)), len(b))
        ti = np.tile(b, len(q_lo))
        qi, ti = _overlap(q, t, qi, ti, range(q_lo.shape[1]))
        parts_q.append(qi)
        parts_t.append(ti)
        small = (~big).nonzero()[0]
    else:
        small = None
    if small is None or len(small):
        qi, ti = _grid_pairs(q, t, small, cell)
        qi, ti = _overlap_xy(q, t, qi, ti)
        qi, ti = _overlap(q, t, qi, ti, _z_axes(q, t, small))
        parts_q.append(qi)
        parts_t.append(ti)
    if len(parts_q) == 1:
        return parts_q[0], parts_t[0]
    return np.concatenate(parts_q), np.concatenate(parts_t)


def _z_axes(
    q: tuple[np.ndarray, np.ndarray], t: tuple[np.ndarray, np.ndarray], small: np.ndarray | None
) -> range:
    """The axes past x and y the grid's pairs must still be tested on: none when every
    query's range overlaps every target's on each of them (robots on one floor)."""
    dims = len(q[0])
    for axis in range(2, dims):
        t_lo, t_hi = (
            (t[0][axis], t[1][axis]) if small is None else (t[0][axis][small], t[1][axis][small])
        )
        if not (q[0][axis].max() <= t_hi.min() and t_lo.max() <= q[1][axis].min()):
            return range(2, dims)
    return range(0)


def _grid_pairs(
    q: tuple[np.ndarray, np.ndarray],
    t: tuple[np.ndarray, np.ndarray],
    small: np.ndarray | None,
    cell: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Candidate pairs of :func:`box_pairs` for the targets ``small`` (None: all; each
    spanning few cells): every target whose centre lies within a query grown by the reach."""
    if small is None:
        t_lo, t_hi = t
    else:
        t_lo, t_hi = (t[0][:2, small], t[1][:2, small])
    centre = (0.5 * (t_lo[0] + t_hi[0]), 0.5 * (t_lo[1] + t_hi[1]))
    # A target reaching a query has its centre within the query grown by this (rounding
    # covered by the slack).
    reach = [0.5 * float((t_hi[a] - t_lo[a]).max()) * (1.0 + 1e-9) + 1e-9 for a in (0, 1)]
    # Runs along the axis the queries' windows are longer on; strips across the other.
    window = [float((q[1][a] - q[0][a]).mean()) + 2.0 * reach[a] for a in (0, 1)]
    run, strip = (0, 1) if window[0] >= window[1] else (1, 0)
    origin = [float(centre[a].min()) for a in (0, 1)]
    extent = [float(centre[a].max()) - origin[a] for a in (0, 1)]
    size = [cell * _CELL_SHARE] * 2
    cells_wanted = _CELLS_PER_TARGET * len(centre[0]) + 1024
    grow = (extent[0] / size[0] + 1.0) * (extent[1] / size[1] + 1.0) / cells_wanted
    if grow > 1.0:
        size = [s * float(np.sqrt(grow)) * 1.5 for s in size]
    inv = [1.0 / s for s in size]
    n = [int(extent[a] * inv[a]) + 1 for a in (0, 1)]
    k_run = ((centre[run] - origin[run]) * inv[run]).astype(np.int64)
    k_strip = ((centre[strip] - origin[strip]) * inv[strip]).astype(np.int64)
    key = k_strip * n[run] + k_run
    n_cells = n[0] * n[1]
    # Up to 65,536 cells the keys fit 16 bits, which numpy sorts by radix (linear time).
    order = (key.astype(np.uint16) if n_cells <= 65536 else key).argsort(kind="stable")
    count = np.bincount(key, minlength=n_cells)
    end = np.cumsum(count)
    by_cell = order if small is None else small[order]
    # Each query's cells, clipped to the grid (outside it: nothing to meet).
    lo = [(q[0][a] - reach[a] - origin[a]) * inv[a] for a in (0, 1)]
    hi = [(q[1][a] + reach[a] - origin[a]) * inv[a] for a in (0, 1)]
    inside = (hi[0] >= 0.0) & (lo[0] < n[0]) & (hi[1] >= 0.0) & (lo[1] < n[1])
    qs = inside.nonzero()[0]
    if len(qs) < len(inside):
        if not len(qs):
            return _EMPTY, _EMPTY
        lo, hi = [v[qs] for v in lo], [v[qs] for v in hi]
    # Non-negative after the clip, so truncation is the floor.
    r_lo = np.maximum(lo[run], 0.0).astype(np.int64)
    r_hi = np.minimum(hi[run], n[run] - 1).astype(np.int64)
    s_lo = np.maximum(lo[strip], 0.0).astype(np.int64)
    s_hi = np.minimum(hi[strip], n[strip] - 1).astype(np.int64)
    strips = s_hi - s_lo + 1
    if np.count_nonzero(strips - 1):  # (query, strip) entries
        q_at = np.repeat(np.arange(len(qs)), strips)
        s = np.repeat(s_lo, strips) + _ramps(strips, len(q_at))
        r_lo, r_hi = r_lo[q_at], r_hi[q_at]
        qs = qs[q_at]
    else:
        s = s_lo
    base = s * n[run]
    stop = end[base + r_hi]
    first = base + r_lo
    start = end[first] - count[first]
    size_ = stop - start
    hit = size_.nonzero()[0]
    if len(hit) < len(size_):
        qs, start, size_ = qs[hit], start[hit], size_[hit]
    qi = np.repeat(qs, size_)
    # Positions start, start + 1, ... of each run in the sorted targets.
    at = np.arange(len(qi)) - np.repeat(np.cumsum(size_) - size_ - start, size_)
    return qi, by_cell[at]


def _ramps(lengths: np.ndarray, total: int) -> np.ndarray:
    """0, 1, ..., lengths[0] - 1, 0, 1, ... (``total`` = the lengths' sum)."""
    return np.arange(total) - np.repeat(np.cumsum(lengths) - lengths, lengths)


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
        obstacle_rows: np.ndarray,
        o_box: tuple[np.ndarray, np.ndarray],
        static: tuple[np.ndarray, np.ndarray],
        own: np.ndarray,
        shift: Callable[[np.ndarray], np.ndarray],
    ) -> None:
        """Bring the pair list up to date with this step's boxes.

        Args:
            key: Changes whenever the static boxes change (their count and a version).
            field_rows: (M,) store rows of the fields' owners.
            f_box: (M, 3) minima and maxima of the fields (warning field, z band).
            obstacle_rows: (N,) store rows of the moving obstacles.
            o_box: (N, 3) their minima and maxima.
            static: (S, 3) minima and maxima of the static boxes.
            own: (M,) each field's owner's index among the obstacles, -1 for none (that pair
                is never listed).
            shift: Maps store rows to how far each moves in :data:`AHEAD` steps ((K, 3) m);
                asked only for the boxes grown in this step (most steps grow none).
        """
        same = (
            key == self._key
            and np.array_equal(field_rows, self._fields)
            and np.array_equal(obstacle_rows, self._rows)
        )
        if not same:
            self._build(key, field_rows, f_box, obstacle_rows, o_box, static, own, shift)
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
            self._build(key, field_rows, f_box, obstacle_rows, o_box, static, own, shift)
            return
        self._patch(f_out, o_out, f_box, o_box, own, shift)

    def _build(
        self,
        key: tuple[int, ...],
        field_rows: np.ndarray,
        f_box: tuple[np.ndarray, np.ndarray],
        obstacle_rows: np.ndarray,
        o_box: tuple[np.ndarray, np.ndarray],
        static: tuple[np.ndarray, np.ndarray],
        own: np.ndarray,
        shift: Callable[[np.ndarray], np.ndarray],
    ) -> None:
        self.builds += 1
        self._key = key
        self._fields = field_rows.copy()
        self._rows = obstacle_rows.copy()
        self._gf = _grown(*f_box, shift(field_rows))
        lo, hi = _grown(*o_box, shift(obstacle_rows))
        self._go = (np.concatenate((lo, static[0])), np.concatenate((hi, static[1])))
        # A typical field's size: the median of the longer side (1-D columns: fast).
        gf_lo, gf_hi = self._gf
        side = np.maximum(gf_hi[:, 0] - gf_lo[:, 0], gf_hi[:, 1] - gf_lo[:, 1])
        self._cell = max(float(np.median(side)), 0.05) if len(side) else 1.0
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
        o_box: tuple[np.ndarray, np.ndarray],
        own: np.ndarray,
        shift: Callable[[np.ndarray], np.ndarray],
    ) -> None:
        """Grow the escaped boxes again and join them against everything."""
        self.patches += 1
        gf_lo, gf_hi = self._gf
        go_lo, go_hi = self._go
        fi, oi = f_out.nonzero()[0], o_out.nonzero()[0]
        lo, hi = _grown(f_box[0][fi], f_box[1][fi], shift(self._fields[fi]))
        gf_lo[fi], gf_hi[fi] = lo, hi
        lo, hi = _grown(o_box[0][oi], o_box[1][oi], shift(self._rows[oi]))
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
