"""Frame buffers of a trace: poses copied out of the state store, a chunk of frames at a time.

The step loop fills a :class:`FrameBuffer` (:meth:`FrameBuffer.capture`, a few numpy
operations per frame, no loop over bodies); the record thread (``file.py``) writes a full
one as a FRAMES record while the step loop fills the other buffer of its layout's pool.
"""

from __future__ import annotations

import queue
from typing import Any

import numpy as np

from fleet_async.core.view.trace.format import (
    BYTES_PER_BODY_FRAME,
    FRAMES_HEADER,
    YAW_SCALE,
    padding,
)

__all__ = ["FrameBuffer", "HeadingTracker"]

_CHUNK_BYTES = 4 << 20  # frame bytes buffered before a FRAMES record is written
_MAX_CHUNK_FRAMES = 256


def yaw_units(quat: np.ndarray, scratch: np.ndarray, out: np.ndarray) -> None:
    """``out`` = the int16 yaw (units of YAW_SCALE) of (M, 4) float32 quaternions.

    float32 is ample for a 0.0055-degree resolution and makes ``arctan2`` three times cheaper
    than in float64. ``scratch`` is a (3, >= M) float32 work array.
    """
    m = len(quat)
    x, y, z, w = quat[:, 0], quat[:, 1], quat[:, 2], quat[:, 3]
    a, b, c = scratch[0, :m], scratch[1, :m], scratch[2, :m]
    # yaw = atan2(2 (w z + x y), 1 - 2 (y^2 + z^2)) = atan2(w z + x y, 1/2 - (y^2 + z^2))
    np.multiply(w, z, out=a)
    np.multiply(x, y, out=c)
    a += c
    np.multiply(y, y, out=b)
    np.multiply(z, z, out=c)
    b += c
    np.subtract(np.float32(0.5), b, out=b)
    np.arctan2(a, b, out=a)
    a *= np.float32(1.0 / YAW_SCALE)
    np.rint(a, out=a)
    out[...] = a


class HeadingTracker:
    """The int16 yaws of one layout's bodies, recomputed only where the orientation changed.

    Most bodies of a fleet keep their heading from one step to the next (driving straight,
    waiting, parked), so each frame compares the float32 quaternions with the frame before's
    (two 64-bit words per body) and runs the trigonometry only on the rows that differ, or on
    all of them when more than a quarter do (gathering rows costs more than it saves then).
    """

    def __init__(self, n: int) -> None:
        self._quats = np.empty((2, n, 4), dtype=np.float32)
        self._current = 0
        self._valid = False
        self._yaw = np.zeros(n, dtype=np.int16)
        self._scratch = np.empty((3, n), dtype=np.float32)

    def update(self, orientation: np.ndarray, out: np.ndarray) -> None:
        """``out`` = the yaws of (N, 4) float64 ``orientation`` rows (the state store's)."""
        n = len(self._yaw)
        quat = self._quats[self._current]
        quat[...] = orientation
        if not self._valid:
            yaw_units(quat, self._scratch, self._yaw)
        else:
            ne = quat.view(np.uint64) != self._quats[self._current ^ 1].view(np.uint64)
            changed = np.flatnonzero(ne[:, 0] | ne[:, 1])
            if 4 * len(changed) > n:
                yaw_units(quat, self._scratch, self._yaw)
            elif len(changed):
                part = np.empty(len(changed), dtype=np.int16)
                yaw_units(quat[changed], self._scratch, part)
                self._yaw[changed] = part
        out[...] = self._yaw
        self._current ^= 1
        self._valid = True


class FrameBuffer:
    """Up to K frames of N bodies as numpy arrays, written as one FRAMES record.

    The step loop fills it (:meth:`capture`); the writer thread writes it (:meth:`payload`)
    while the step loop fills the other buffer of the layout's pool.
    """

    def __init__(
        self,
        ids: np.ndarray,
        rows: np.ndarray,
        pool: queue.Queue[FrameBuffer],
        headings: HeadingTracker,
    ) -> None:
        n = len(ids)
        self.ids = ids
        self.pool = pool
        self._headings = headings  # shared by the buffers of one layout
        # Contiguous rows (the usual case) are read by slicing, which is cheaper than gathering.
        contiguous = n > 0 and int(rows[-1]) - int(rows[0]) == n - 1
        self.sel: slice | np.ndarray = (
            slice(int(rows[0]), int(rows[-1]) + 1) if contiguous else rows
        )
        self.capacity = max(
            1, min(_MAX_CHUNK_FRAMES, _CHUNK_BYTES // max(1, BYTES_PER_BODY_FRAME * n))
        )
        self.steps = np.zeros(self.capacity, dtype=np.int32)
        self.pos = np.zeros((self.capacity, n, 3), dtype=np.float32)
        self.yaw = np.zeros((self.capacity, n), dtype=np.int16)
        self.flags = np.zeros((self.capacity, n), dtype=np.uint8)
        self.count = 0
        self._ne = np.empty((n, 3), dtype=bool)
        # object id -> index in the frame (-1: not in it), for setting flag bits in bulk
        self.lookup = np.full(int(ids.max()) + 1 if n else 0, -1, dtype=np.int64)
        self.lookup[ids] = np.arange(n)

    def indices_of(self, object_ids: Any) -> np.ndarray:
        """Frame indices of the given object ids that are in this frame's layout."""
        ids = np.fromiter(object_ids, dtype=np.int64)
        ids = ids[(ids >= 0) & (ids < len(self.lookup))]
        where = self.lookup[ids]
        return where[where >= 0]

    def capture(
        self,
        step: int,
        store: Any,
        extra_flags: np.ndarray | None,
        previous: tuple[np.ndarray, np.ndarray] | None,
    ) -> None:
        """Copy one frame out of the state store (the simulation's thread).

        Only what the frame needs crosses the memory bus: float32 positions and the int16
        yaw (a step at fleet scale has just evicted the store from the caches, so this is
        bound by memory traffic more than by arithmetic). FLAG_MOVING compares with the frame
        before, which is still in the cache: this buffer's previous frame, or ``previous``
        (positions, yaws) for the first frame of a chunk.
        """
        k, sel = self.count, self.sel
        self.steps[k] = step
        pos = self.pos[k]
        pos[...] = store.position[sel]
        yaw = self.yaw[k]
        self._headings.update(store.orientation[sel], yaw)
        flags = self.flags[k]
        before = (self.pos[k - 1], self.yaw[k - 1]) if k else previous
        if before is None:
            flags[...] = 0
        else:
            moved = flags.view(bool)
            np.not_equal(yaw, before[1], out=moved)  # FLAG_MOVING is bit 0
            # Column by column: ndarray.any(axis=1) on (N, 3) is several times slower.
            ne = self._ne
            np.not_equal(pos, before[0], out=ne)
            moved |= ne[:, 0]
            moved |= ne[:, 1]
            moved |= ne[:, 2]
        if extra_flags is not None:
            flags |= extra_flags
        self.count += 1

    def payload(self) -> list[Any]:
        """The FRAMES payload as buffers to write in order (the writer thread)."""
        k, n = self.count, len(self.ids)
        return [
            FRAMES_HEADER.pack(k, n),
            self.steps[:k].view(np.uint8).data,
            self.pos[:k].reshape(-1).view(np.uint8).data,
            self.yaw[:k].reshape(-1).view(np.uint8).data,
            bytes(padding(2 * k * n)),
            self.flags[:k].reshape(-1).data,
        ]

    def last_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the last frame's positions and yaws."""
        return self.pos[self.count - 1].copy(), self.yaw[self.count - 1].copy()

    def release(self) -> None:
        """Written: empty, back to the pool of its layout."""
        self.count = 0
        self.pool.put(self)
