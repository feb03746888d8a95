"""The kinematic engine's per-slot storage: one row of columns per slot.

Every float column (limits, the segment's poses and profile, velocity commands) lives side by
side in one matrix and is reached through named views (``table.p0[slot]``), so a step gathers
what the moving slots need in one call instead of one per column: at 100 robots a step is a
few dozen numpy calls, and each costs about a microsecond whatever its size. The columns a
step reads come first, so the gather copies no more than those, and the matrix is stored a
column to a row, (k, slots), so each gathered column is contiguous for the arithmetic (both
count at 10,000 robots). Integer and flag columns (store row, controller kind, mode) are
arrays of their own. Which slots move is cached until a mode changes.
"""

from __future__ import annotations

import numpy as np

from fleet_async.core.motion.segments import EPS_LEN as _EPS_LEN
from fleet_async.core.motion.segments import PROFILE_TERMS, profile_terms

__all__ = [
    "AT",
    "COLUMNS",
    "IDLE",
    "POSE",
    "PROFILE_AT",
    "SEGMENT_COLUMNS",
    "VELOCITY",
    "SlotTable",
    "flat_rows",
]

IDLE, VELOCITY, POSE = 0, 1, 2  # a slot's mode

# The float columns, name -> width, in their order in the matrix: first what every step of a
# moving slot reads (_MOVE_END), then what a turning one reads too (_TURN_END), then the rest.
# u: progress along the segment in [0, 1]; steps: steps of the segment taken so far; u_peak:
# cruise rate of u (1/s); u_t_acc: s spent accelerating (and braking); u_t_end: s the segment
# takes; theta, axis, sl_*: the rotation and its slerp terms; cmd, vel: body-frame command and
# velocity (vx, vy, vz, wz) in VELOCITY mode. dp (p1 - p0), the profile's terms (as
# trapezoid_progress takes them) and t_arrive (the time from which the segment has ended) are
# derived when a segment starts (see _derive) and never saved.
_MOVE = {
    "u": 1,
    "steps": 1,
    "t_arrive": 1,
    "u_t_end": 1,
    **dict.fromkeys(PROFILE_TERMS, 1),
    **dict.fromkeys(("p0", "dp", "p1"), 3),
    "theta": 1,
}
_TURN = {
    **dict.fromkeys(("q0", "q1", "q_goal"), 4),
    "axis": 3,
    "sl_dot": 1,
    "sl_theta": 1,
    "sl_sin": 1,
}
_REST = {
    "u_peak": 1,
    "u_t_acc": 1,
    **dict.fromkeys(("vmax", "amax", "wmax", "alpha"), 3),
    "cmd": 4,
    "vel": 4,
}
_DERIVED = ("dp", *PROFILE_TERMS, "t_arrive")
_OTHERS: dict[str, tuple[type, int | bool]] = {
    "row": (np.int64, -1),
    "kind": (np.int8, 0),
    "mode": (np.int8, IDLE),
    "lin_scalar": (np.bool_, True),
    "ang_scalar": (np.bool_, True),
}
_WIDTHS = {**_MOVE, **_TURN, **_REST}
COLUMNS = (*(name for name in _WIDTHS if name not in _DERIVED), *_OTHERS)
"""The columns a checkpoint holds (``get_state``)."""


def _starts() -> dict[str, int]:
    """Column name -> the index of its first entry in the float matrix."""
    starts: dict[str, int] = {}
    at = 0
    for name, width in _WIDTHS.items():
        starts[name] = at
        at += width
    return starts


_START = _starts()
_WIDTH = sum(_WIDTHS.values())
_MOVE_END = sum(_MOVE.values())  # the first columns: all a moving slot's step reads
_TURN_END = _MOVE_END + sum(_TURN.values())  # ... and all a turning one reads
AT: dict[str, slice | int] = {
    name: start if _WIDTHS[name] == 1 else slice(start, start + _WIDTHS[name])
    for name, start in _START.items()
}
"""Column name -> its place in the float matrix (an int for a width-1 column)."""
PROFILE_AT = slice(_START[PROFILE_TERMS[0]], _START[PROFILE_TERMS[-1]] + 1)
"""The profile's terms, in trapezoid_progress's order."""


SEGMENT_COLUMNS = (*_MOVE, *_TURN, "u_peak", "u_t_acc")
"""The columns a segment's start writes (``SlotTable.write_segment``), in their order in the
matrix: the first rows of it, so that one slot's segment is one strided write."""
_SEGMENT_END = sum(_WIDTHS[name] for name in SEGMENT_COLUMNS)
assert tuple(_WIDTHS)[: len(SEGMENT_COLUMNS)] == SEGMENT_COLUMNS

_XYZ = np.arange(3)[:, None]


def flat_rows(rows: np.ndarray) -> np.ndarray:
    """(3, len(rows)) indices of x, y, z of ``rows`` in an (N, 3) array seen flat."""
    return rows * 3 + _XYZ


class SlotTable:
    """Per-slot columns, grown together by :meth:`_alloc`; the base of the kinematic engine."""

    # Views into the float matrix (_WIDTHS), then the columns of _OTHERS.
    row: np.ndarray
    kind: np.ndarray
    mode: np.ndarray
    vmax: np.ndarray
    amax: np.ndarray
    wmax: np.ndarray
    alpha: np.ndarray
    p0: np.ndarray
    p1: np.ndarray
    dp: np.ndarray
    axis: np.ndarray
    q0: np.ndarray
    q1: np.ndarray
    q_goal: np.ndarray
    u: np.ndarray
    steps: np.ndarray
    u_peak: np.ndarray
    u_t_acc: np.ndarray
    u_t_end: np.ndarray
    t_arrive: np.ndarray
    theta: np.ndarray
    sl_dot: np.ndarray
    sl_theta: np.ndarray
    sl_sin: np.ndarray
    lin_scalar: np.ndarray
    ang_scalar: np.ndarray
    cmd: np.ndarray
    vel: np.ndarray

    def __init__(self) -> None:
        self._high = 0  # slots below this have been used
        self._floats = np.zeros((_WIDTH, 0))  # column-major: one row of the matrix per column
        self._moving: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        self._scale: np.ndarray | None = None  # per slot: time scale of this step (fields)

    def _alloc(self, cap: int) -> None:
        floats = np.zeros((_WIDTH, cap))
        floats[:, : self._floats.shape[1]] = self._floats
        self._floats = floats
        for name, place in AT.items():
            setattr(self, name, floats[place].T)  # (cap, width) views; (cap,) for width 1
        # What a step reads, as blocks to gather with take(slots, axis=1): a C-ordered
        # (columns, slots) copy, so each column the step computes on is contiguous.
        self._move_block = floats[:_MOVE_END]
        self._turn_block = floats[:_TURN_END]
        for name, (dtype, fill) in _OTHERS.items():
            new: np.ndarray = np.full(cap, fill, dtype=dtype)
            old = getattr(self, name, None)
            if old is not None:
                new[: len(old)] = old
            setattr(self, name, new)
        self._moving = None
        self._scale = None  # the next step's scale is set again (set_time_scale)

    def _set_mode(self, slot: int, mode: int) -> None:
        """Change a slot's mode (and forget the cached sets of moving slots if it changed)."""
        if self.mode[slot] != mode:
            self.mode[slot] = mode
            self._moving = None

    def _moving_slots(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(pose slots, their store rows, the rows' flat indices, velocity slots), cached until
        a mode changes. The flat indices, (3, slots), address x, y, z of each row of an
        (N, 3) store column seen flat: a scatter through them is several times cheaper than
        one through ``column[rows]``."""
        if self._moving is None:
            mode = self.mode[: self._high]
            pose = (mode == POSE).nonzero()[0]
            rows = self.row[pose]
            self._moving = (pose, rows, flat_rows(rows), (mode == VELOCITY).nonzero()[0])
        return self._moving

    def path_rows(self) -> np.ndarray:
        """Store rows of the slots following a path (POSE mode), ascending by slot."""
        return self._moving_slots()[1]

    def commanded_rows(self) -> np.ndarray:
        """Store rows of the slots following a path or a velocity command (what the safety
        fields watch): the POSE slots' rows, then the VELOCITY slots'."""
        _, rows, _, velocity = self._moving_slots()
        return np.concatenate((rows, self.row[velocity])) if len(velocity) else rows

    def segment_directions(self) -> tuple[np.ndarray, np.ndarray]:
        """(store rows, (K, 2) unit ground-plane directions) of the path-following slots whose
        current segment moves them (turns in place have none)."""
        pose, rows, _, _ = self._moving_slots()
        d = self.dp[pose, :2]
        norm = np.hypot(d[:, 0], d[:, 1])
        keep = norm > _EPS_LEN
        return rows[keep], d[keep] / norm[keep, None]

    def set_time_scale(self, scale_of_row: np.ndarray | None) -> None:
        """Scale the next step's progress along each slot's path by its store row's entry.

        0 holds a slot where it is (its path and profile wait, to resume from where they
        stopped), 0.5 drives it at half its speed; None (the default) drives every slot as
        planned. Set before each step by the safety fields (``collision/safety.py``). A
        velocity command is scaled too: 0 stops the slot at once (its velocity drops to zero),
        a fraction caps the command, from which the slot ramps within its limits.

        Args:
            scale_of_row: (rows,) floats indexed by store row, covering every slot's row.
        """
        if scale_of_row is None:
            self._scale = None
            return
        rows = self.row  # every slot's, so a slot added during the step has an entry
        known = (rows >= 0) & (rows < len(scale_of_row))
        self._scale = np.where(known, scale_of_row[np.where(known, rows, 0)], 1.0)

    def write_segment(self, slot: int, values: list[float]) -> None:
        """Write a starting segment's columns (``SEGMENT_COLUMNS``, derived ones included) in
        one call: a slot starts segments in Python, where each numpy write costs more than
        the arithmetic."""
        self._floats[:_SEGMENT_END, slot] = values

    def segment_matrix(self, count: int) -> np.ndarray:
        """Zeros shaped for the segment columns of ``count`` slots (``write_segments``)."""
        return np.zeros((_SEGMENT_END, count))

    def write_segments(self, slots: np.ndarray, columns: np.ndarray) -> None:
        """``write_segment`` for many slots: ``columns[:, k]`` are ``slots[k]``'s, in the
        matrix's rows (``AT``)."""
        self._floats[:_SEGMENT_END, slots] = columns

    def _derive(self, slot: int) -> None:
        """Work out a slot's derived columns (``_DERIVED``) from its segment's columns."""
        at, row = AT, self._floats[:, slot]
        row[at["dp"]] = self.p1[slot] - self.p0[slot]
        t_end = float(self.u_t_end[slot])
        terms = profile_terms(float(self.u_peak[slot]), float(self.u_t_acc[slot]), t_end)
        for name, value in zip(PROFILE_TERMS, terms, strict=True):
            row[at[name]] = value
        row[at["t_arrive"]] = t_end - 1e-9
