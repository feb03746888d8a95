"""The simulation's collision methods (the reference API's names), on its CollisionSystem.

Mixed into the simulation kernel: checks on demand, the broad phase alone, AABBs, active pairs,
the check frequency and the spatial hash cell size. The kernel runs the checks in its
``collision_check`` phase; handlers of ``collision_started`` / ``collision_ended`` are told by
the system itself (``system.py``).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from fleet_async.core.base.types import SpatialHashCellSizeMode, coerce_enum

if TYPE_CHECKING:
    from fleet_async.core.collision.system import CollisionListener, CollisionSystem
    from fleet_async.core.world.world import World

__all__ = ["CollisionApi"]


class CollisionApi:
    """Collision checks and settings of a simulation (mixed into the simulation kernel)."""

    # Provided by the simulation kernel.
    _collision: CollisionSystem
    _collision_count: int
    _world: World

    @property
    def collision_count(self) -> int:
        """Collisions that started since the last ``initialize_simulation``."""
        return self._collision_count

    def note_collisions(self, started: int) -> None:
        """Count collisions that started (called by the collision system)."""
        self._collision_count += started

    def get_aabbs(self) -> dict[int, tuple[list[float], list[float]]]:
        """``{object_id: (aabb_min, aabb_max)}`` of every object taking part in collisions."""
        return self._collision.get_aabbs()

    def get_aabb_bounds(
        self, object_ids: Sequence[int] | None = None
    ) -> tuple[list[float], list[float]] | None:
        """(min, max) corners (m, world frame) of the union of the objects' AABBs.

        Args:
            object_ids: The objects (default: every object taking part in collisions). Ids of
                objects without an AABB (collision mode DISABLED, removed) are skipped.

        Returns:
            The two corners, or None when no object given has an AABB.
        """
        rows = None
        if object_ids is not None:
            objects = (self._world.get(i) for i in object_ids)
            rows = np.fromiter(
                (obj.state_row for obj in objects if obj is not None), dtype=np.int64
            )
        bounds = self._collision.bounds(rows)
        return None if bounds is None else (bounds[0].tolist(), bounds[1].tolist())

    def filter_aabb_pairs(
        self,
        ignore_static: bool | None = None,
        moved_objects: set[int] | None = None,
        return_profiling: bool = False,
    ) -> tuple[list[tuple[int, int]], dict[str, float] | None]:
        """Broad phase only: object-id pairs whose AABBs overlap and involve a moved object.

        Args:
            ignore_static: Skip pairs with a STATIC object (default: params).
            moved_objects: Object ids to treat as moved (default: those that moved).
            return_profiling: Also return ``{get_aabbs, spatial_hashing, aabb_filtering,
                total}`` in ms.
        """
        t0 = time.perf_counter()
        rows, timings = self._collision.filter_pairs(ignore_static, moved_objects)
        ids = self._world.store.object_id[rows].tolist() if len(rows) else []
        pairs = sorted(tuple(sorted(pair)) for pair in ids)
        timings["total"] = (time.perf_counter() - t0) * 1e3
        return pairs, timings if return_profiling else None

    def check_collisions(
        self,
        collision_color: list[float] | None = None,
        ignore_static: bool | None = None,
        return_profiling: bool = False,
    ) -> tuple[list[tuple[int, int]], dict[str, float] | None]:
        """Run a collision check now; return the active pairs (object ids, i < j), and with
        ``return_profiling`` ``{get_aabbs, spatial_hashing, aabb_filtering, contact_points,
        total}`` in ms."""
        pairs, timings = self._collision.check(ignore_static, collision_color)
        timings.pop("events", None)  # the step's profile reports it as events_collision
        return pairs, timings if return_profiling else None

    def get_active_collision_pairs(self) -> list[tuple[int, int]]:
        """Pairs (object_id_i < object_id_j) in contact as of the last check."""
        return self._collision.active_pairs()

    def add_collision_listener(self, listener: CollisionListener) -> None:
        """Call ``listener(ended, started)`` after every check that changed the active pairs.

        ``ended`` and ``started`` are (K, 2) int64 numpy arrays of object-id pairs ``(a, b)``
        with ``a < b``, in ascending order (``ended.tolist()`` gives plain pairs); a pair whose
        object left the simulation ends at the next check. Listeners must not modify them.
        One call per check however many pairs changed, made from the active pairs' arrays
        without a Python loop over pairs, so a recorder that wants every contact of a large
        fleet pays per check rather than per ``collision_started`` / ``collision_ended`` event
        (and nothing at all while nobody listens). Listeners run after the events, in the
        order they were added.
        """
        self._collision.listeners.append(listener)

    def remove_collision_listener(self, listener: CollisionListener) -> bool:
        """Stop calling ``listener``; return whether it was added."""
        if listener in self._collision.listeners:
            self._collision.listeners.remove(listener)
            return True
        return False

    def set_collision_check_frequency(self, frequency: float | None = None) -> None:
        """Check every step (None), never (0), or at ``frequency`` Hz of sim time."""
        self._collision.set_frequency(frequency)

    def set_collision_spatial_hash_cell_size_mode(
        self, mode: SpatialHashCellSizeMode | str | None = None, cell_size: float | None = None
    ) -> float:
        """Switch the hash cell size mode (CONSTANT needs ``cell_size``) and recompute it.

        Returns:
            The cell size now in force (m, > 0).
        """
        if mode is not None:
            self._collision.cell_mode = coerce_enum(SpatialHashCellSizeMode, mode, "mode")
        if cell_size is not None:
            if not (isinstance(cell_size, (int, float)) and cell_size > 0):
                raise ValueError(f"cell_size: expected a number > 0 (m), got {cell_size!r}")
            self._collision.cell_size = float(cell_size)
        elif (
            self._collision.cell_mode is SpatialHashCellSizeMode.CONSTANT
            and not self._collision.cell_size
        ):
            raise ValueError(
                "set_collision_spatial_hash_cell_size_mode: CONSTANT mode needs a cell_size"
            )
        rows = self._collision.prepare_rows()
        if self._collision.cell_mode is SpatialHashCellSizeMode.CONSTANT:
            return float(self._collision.cell_size or 1.0)
        return self._collision.resolve_cell_size(rows, recompute=True)
