"""The kinematic state store: every body's state as rows of numpy arrays.

``SimObject`` and ``Agent`` are thin handles onto one row each. Vectorised code (controllers,
the attachment pass, the collision broad phase) reads and writes whole columns at once; nothing
on the hot path loops over objects in Python.

Rows are stable for an object's lifetime. Freed rows are reused smallest-first, so the layout
after any sequence of spawns and removals is a function of that sequence alone (determinism).
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence

import numpy as np

__all__ = ["KinematicState"]

# Collision mode codes stored in ``KinematicState.collision_mode`` (int8 column).
COLLISION_CODES = {"normal_3d": 0, "normal_2d": 1, "static": 2, "disabled": 3}


class KinematicState:
    """Structure-of-arrays store of poses, velocities and flags.

    Columns (``N`` = capacity; only rows with ``active`` set are meaningful):
        position (N, 3) float64, world frame, metres.
        orientation (N, 4) float64, unit quaternion (x, y, z, w), world frame.
        velocity (N, 3) float64, world frame, m/s.
        angular_velocity (N, 3) float64, world frame, rad/s.
        body_id (N,) int64, PyBullet body unique id (-1 for none).
        object_id (N,) int64, simulation object id.
        collision_mode (N,) int8, see ``COLLISION_CODES``.
        kinematic (N,) bool, pose is owned by this store (not by PyBullet dynamics).
        active (N,) bool, row in use.
        dirty (N,) bool, PyBullet's view of the body is stale.
        moved (N,) bool, pose changed since the last collision check.
        written (N,) bool, pose written since the attachment pass last looked (set by every
            pose write: ``mark_moved``, allocation, PyBullet's read-back; cleared only by that
            pass, whose carried objects follow the rows it flags).
    """

    _FLOAT_COLUMNS = ("position", "orientation", "velocity", "angular_velocity")

    def __init__(self, capacity: int = 64) -> None:
        capacity = max(int(capacity), 1)
        # Every column stays one C-ordered array (grown by copying): the kinematic engine
        # writes positions through flat views of them (column.reshape(-1)).
        self.position = np.zeros((capacity, 3))
        self.orientation = np.zeros((capacity, 4))
        self.orientation[:, 3] = 1.0
        self.velocity = np.zeros((capacity, 3))
        self.angular_velocity = np.zeros((capacity, 3))
        self.body_id = np.full(capacity, -1, dtype=np.int64)
        self.object_id = np.full(capacity, -1, dtype=np.int64)
        self.collision_mode = np.zeros(capacity, dtype=np.int8)
        self.kinematic = np.ones(capacity, dtype=bool)
        self.active = np.zeros(capacity, dtype=bool)
        self.dirty = np.zeros(capacity, dtype=bool)
        self.moved = np.zeros(capacity, dtype=bool)
        self.written = np.zeros(capacity, dtype=bool)
        self._free: list[int] = []
        self._high_water = 0
        self.layout_version = 0
        """Bumped whenever a row is claimed or freed or changes collision mode (lets the
        collision system skip re-scanning the rows when nothing of the kind happened)."""

    @property
    def capacity(self) -> int:
        """Number of rows allocated (used or not)."""
        return int(self.active.shape[0])

    @property
    def count(self) -> int:
        """Number of rows in use."""
        return self._high_water - len(self._free)

    @property
    def high_water(self) -> int:
        """One past the highest row ever used; slices ``[:high_water]`` cover every live row."""
        return self._high_water

    def allocate(
        self,
        object_id: int,
        body_id: int,
        position: Sequence[float] | np.ndarray,
        orientation: Sequence[float] | np.ndarray,
        *,
        kinematic: bool = True,
        collision_code: int = 0,
    ) -> int:
        """Claim a row for one object and fill it; return the row index."""
        if self._free:
            row = heapq.heappop(self._free)
            # A reused row keeps what its last object left: reset everything.
            self.velocity[row] = 0.0
            self.angular_velocity[row] = 0.0
            self.collision_mode[row] = collision_code
            self.kinematic[row] = kinematic
            self.dirty[row] = False
        else:
            row = self._high_water
            if row >= len(self.active):
                self._reserve(row + 1)
            self._high_water += 1
            # A fresh row holds the defaults _reserve filled in (zero velocities, mode 0,
            # kinematic, clean): one spawn of thousands costs only the writes below.
            if collision_code:
                self.collision_mode[row] = collision_code
            if not kinematic:
                self.kinematic[row] = False
        self.position[row] = position
        self.orientation[row] = orientation
        self.body_id[row] = body_id
        self.object_id[row] = object_id
        self.active[row] = True
        self.moved[row] = True
        self.written[row] = True
        self.layout_version += 1
        return row

    def allocate_many(
        self,
        object_ids: np.ndarray,
        body_ids: np.ndarray,
        positions: np.ndarray,
        orientations: np.ndarray,
        *,
        kinematic: bool = True,
        collision_code: int = 0,
    ) -> np.ndarray:
        """Claim ``len(object_ids)`` rows in bulk; return their indices in input order."""
        n = len(object_ids)
        reused = [heapq.heappop(self._free) for _ in range(min(n, len(self._free)))]
        fresh = n - len(reused)
        self._reserve(self._high_water + fresh)
        rows = np.array(
            reused + list(range(self._high_water, self._high_water + fresh)), dtype=np.int64
        )
        self._high_water += fresh
        self.position[rows] = positions
        self.orientation[rows] = orientations
        self.velocity[rows] = 0.0
        self.angular_velocity[rows] = 0.0
        self.body_id[rows] = body_ids
        self.object_id[rows] = object_ids
        self.collision_mode[rows] = collision_code
        self.kinematic[rows] = kinematic
        self.active[rows] = True
        self.dirty[rows] = False  # freshly created bodies already sit at this pose in PyBullet
        self.moved[rows] = True  # but the collision system has not seen them yet
        self.written[rows] = True
        self.layout_version += 1
        return rows

    def release(self, row: int) -> None:
        """Return a row to the free list and clear its flags."""
        if not self.active[row]:
            raise ValueError(f"KinematicState.release: row {row} is not in use")
        self.active[row] = False
        self.dirty[row] = False
        self.moved[row] = False
        self.body_id[row] = -1
        self.object_id[row] = -1
        heapq.heappush(self._free, int(row))
        self.layout_version += 1

    def clear(self) -> None:
        """Free every row (used by ``reset``); capacity is kept, and rows hold the defaults of
        fresh ones again (``allocate`` relies on it)."""
        used = slice(0, self._high_water)
        self.velocity[used] = 0.0
        self.angular_velocity[used] = 0.0
        self.collision_mode[used] = 0
        self.kinematic[used] = True
        self.active[:] = False
        self.dirty[:] = False
        self.moved[:] = False
        self.written[:] = False
        self.body_id[:] = -1
        self.object_id[:] = -1
        self._free.clear()
        self._high_water = 0
        self.layout_version += 1

    def set_collision_code(self, row: int, code: int) -> None:
        """Change a row's collision mode code (and flag it moved, so its pairs are re-checked)."""
        self.collision_mode[row] = code
        self.moved[row] = True
        self.layout_version += 1

    def mark_moved(self, rows: int | np.ndarray) -> None:
        """Flag rows whose pose changed: stale in PyBullet, unseen by the collision system."""
        self.dirty[rows] = True
        self.moved[rows] = True
        self.written[rows] = True

    def live_rows(self) -> np.ndarray:
        """Indices of rows in use, ascending."""
        return np.flatnonzero(self.active[: self._high_water])

    def dirty_rows(self) -> np.ndarray:
        """Indices of rows whose PyBullet pose is stale, ascending."""
        return np.flatnonzero(self.dirty[: self._high_water])

    def nbytes(self) -> int:
        """Bytes held by the columns."""
        return (
            sum(
                getattr(self, name).nbytes
                for name in (*self._FLOAT_COLUMNS, "body_id", "object_id", "collision_mode")
            )
            + 5 * self.capacity  # the bool columns: kinematic, active, dirty, moved, written
        )

    def _reserve(self, needed: int) -> None:
        if needed <= self.capacity:
            return
        old_cap = self.capacity
        new_cap = max(needed, 2 * old_cap)
        for name in (*self._FLOAT_COLUMNS, "body_id", "object_id", "collision_mode"):
            old = getattr(self, name)
            grown = np.empty((new_cap, *old.shape[1:]), dtype=old.dtype)
            grown[: old.shape[0]] = old
            fill = -1 if name in ("body_id", "object_id") else 0
            grown[old.shape[0] :] = fill
            setattr(self, name, grown)
        self.orientation[old_cap:, 3] = 1.0
        for name in ("kinematic", "active", "dirty", "moved", "written"):
            old = getattr(self, name)
            grown = np.full(new_cap, name == "kinematic", dtype=bool)  # fresh rows: kinematic
            grown[: old.shape[0]] = old
            setattr(self, name, grown)
