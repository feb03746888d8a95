"""Collision detection: AABBs from the state store, broad phase, narrow phase, events.

A check: register rows new to the collision system (``geometry.py``), refresh the world AABBs
of rows that moved, find candidate pairs that involve a moved row (``broadphase.py``), keep
those whose AABBs overlap, run the narrow phase on the survivors (``narrowphase.py``), and
update the active pairs (``pairs.py``): ``collision_started`` / ``collision_ended`` fire once
per contact. A check in which nothing moved and nothing joined does no array work at all.

With ``SimulationParams.collision_sweep`` the broad phase uses each moved row's AABB swept from
its position at the previous check to its position now, and pairs that are not touching at
the end are asked whether they touched on the way (``NarrowPhase.touched_during``): two robots
that pass through each other within one step are reported.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import pybullet as p

from fleet_async.core.base.compiled import use_numba
from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.types import CollisionDetectionMethod, SpatialHashCellSizeMode
from fleet_async.core.collision.broadphase import auto_cell_size, candidate_pairs
from fleet_async.core.collision.geometry import CollisionGeometry
from fleet_async.core.collision.narrowphase import NarrowPhase
from fleet_async.core.collision.pairs import ActivePairs, decode, id_pairs, pair_codes
from fleet_async.core.world.state import COLLISION_CODES

if TYPE_CHECKING:
    from fleet_async.core.collision.host import CollisionHost

__all__ = ["CollisionListener", "CollisionSystem"]

CollisionListener = Callable[[np.ndarray, np.ndarray], None]
"""Called as ``listener(ended, started)`` once per check that changed the active pairs: each a
(K, 2) int64 array of object ids ``(a, b)``, ``a < b``, in ascending order."""

_STATIC = COLLISION_CODES["static"]
_DISABLED = COLLISION_CODES["disabled"]
_FLAT = COLLISION_CODES["normal_2d"]
_NO_PAIRS = np.empty((0, 2), dtype=np.int64)
_WHOLE_MAX = 1024
_NO_ROWS = np.empty(0, dtype=np.int64)
_SWEPT_CELLS = 7.0  # cells an object may span per axis, swept, and still be hashed


class CollisionSystem:
    """Collision state and checks of one simulation.

    Args:
        sim: The simulation (its state store, client, objects and event bus).
        on_sync: Pushes the given rows' poses to PyBullet.
    """

    def __init__(self, sim: CollisionHost, on_sync: Callable[[np.ndarray], None]) -> None:
        self._sim = sim
        prm = sim.params
        self.frequency = prm.collision_check_frequency
        self.cell_mode = prm.spatial_hash_cell_size_mode
        self.cell_size: float | None = prm.spatial_hash_cell_size
        self.method = prm.resolved_collision_detection_method
        self.margin = prm.collision_margin
        self.multi_cell_threshold = prm.multi_cell_threshold
        self.ignore_static = prm.ignore_static_collision
        self.color_change = prm.enable_collision_color_change
        self.sweep = prm.collision_sweep
        # check_jit's kernels, when numba is used (base/compiled.py)
        self._kernel: Callable[..., Any] | None = None
        self._refresh_kernel: Callable[..., int] | None = None
        if use_numba(prm.kernels):
            from fleet_async.core.collision.check_jit import SharedCellPairs, refresh_upright

            self._kernel = SharedCellPairs()
            self._refresh_kernel = refresh_upright
        pad = self.margin / 2 if self.method is not CollisionDetectionMethod.CONTACT_POINTS else 0.0

        world = sim.world

        def client() -> int:  # checks need no body they do not ask for: none is created here
            return world.client

        self.geometry = CollisionGeometry(pad, client, on_sync, world)
        self.narrow = NarrowPhase(
            self.geometry,
            self.method,
            self.margin,
            client,
            on_sync,
            world.create_pending_bodies_for,
        )
        self._active = ActivePairs()
        self._colors: dict[int, list[Any]] = {}
        self._next_due_step = 0
        self.listeners: list[CollisionListener] = []
        """Told the pairs that ended and started, once per check that changed any."""
        self._layout = -1  # store layout version the cached row sets below belong to
        self._rows = np.empty(0, dtype=np.int64)  # rows taking part, ascending
        self._all_rows = False  # rows == arange(high): views instead of gathers
        self._flat: np.ndarray | None = None  # NORMAL_2D mask over rows, None if none
        self._static: np.ndarray | None = None  # STATIC mask over rows, None if none
        self._unstatic: tuple[np.ndarray, np.ndarray | None] | None = None
        self._plain = False  # no STATIC, no articulated rows: whole-array AABB refresh allowed
        self._start = np.zeros((0, 3))  # row positions at the previous check (sweep)
        # Rows were added, removed or changed mode since the last check. Kept until a check
        # has run: reading AABBs in between (a camera) relays the rows out, not the check.
        self._relaid = False

    @property
    def registrations(self) -> int:
        """Rows registered so far (each reads its body-frame geometry once)."""
        return self.geometry.registrations

    # ----- schedule -----------------------------------------------------------------------

    def set_frequency(self, frequency: float | None) -> None:
        """None: every step; 0: never; f > 0: at f Hz of sim time."""
        if frequency is not None and not (isinstance(frequency, (int, float)) and frequency >= 0):
            raise ValueError(
                f"collision_check_frequency: expected None or a number >= 0 (Hz), got {frequency!r}"
            )
        self.frequency = frequency
        self._next_due_step = 0

    def is_due(self, step: int, timestep: float) -> bool:
        """Whether the check runs in ``step`` (0-based); advances the schedule when it does."""
        if self.frequency is None:
            return True
        if self.frequency == 0 or step < self._next_due_step:
            return False
        self._next_due_step = step + max(1, round(1.0 / (self.frequency * timestep)))
        return True

    def get_state(self) -> dict[str, Any]:
        """Active pairs, the check schedule and the hash cell size (checkpoints)."""
        return {
            "active": self._active.get_state(),
            "next_due_step": self._next_due_step,
            "cell_size": self.cell_size,
        }

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore :meth:`get_state`; registrations are redone at the next check."""
        self._active.set_state(state["active"])
        self._next_due_step = state["next_due_step"]
        self.cell_size = state["cell_size"]

    def idle_steps(self, step: int, limit: int) -> int:
        """How many of the steps ``step, step + 1, ...`` (at most ``limit``) need no check:
        all of them when nothing moved and no row joined or left since the last check (a
        check would find nothing new), else those before the next check falls due."""
        if self.frequency == 0:
            return limit
        store = self._sim.state
        if (
            store.layout_version == self._layout
            and not self._relaid
            and not np.count_nonzero(store.moved[: store.high_water])
        ):
            return limit
        if self.frequency is None:
            return 0
        return max(0, min(limit, self._next_due_step - step))

    def skip(self, step: int, n: int, timestep: float) -> None:
        """Advance the schedule over ``n`` empty steps from ``step`` as if they had run: a
        check falling due among them would have found nothing new, so only its time counts."""
        if self.frequency is None or not self.frequency:
            return
        first = max(step, self._next_due_step)
        end = step + n - 1
        if first > end:
            return
        period = max(1, round(1.0 / (self.frequency * timestep)))
        self._next_due_step = first + ((end - first) // period) * period + period

    def reset(self) -> None:
        """Forget every registration and active pair (simulation reset)."""
        self.geometry.reset()
        self._active.clear()
        self._colors.clear()
        self._next_due_step = 0
        self._layout = -1
        self._relaid = False
        if self.cell_mode is not SpatialHashCellSizeMode.CONSTANT:
            self.cell_size = None

    # ----- rows taking part -----------------------------------------------------------------

    def prepare_rows(self) -> np.ndarray:
        """Register and refresh as a check would; return the rows taking part."""
        self._prepare()
        return self._rows

    def _prepare(self) -> int:
        """Register new / changed rows and refresh moved ones; return how many moved."""
        store = self._sim.state
        high = store.high_water
        if store.layout_version != self._layout:
            self._relayout()
            self._relaid = True
        flags = store.moved[:high]
        if self._refresh_kernel is not None and self._plain:
            geo = self.geometry
            count = self._refresh_kernel(
                store.position,
                store.orientation,
                geo.offsets,
                geo.box,
                geo.aabb,
                geo.exact,
                flags,
                high,
            )
            if count >= 0:
                return count
        moved = flags.nonzero()[0] if np.count_nonzero(flags) else _NO_ROWS
        # Most rows moved, or few rows in all, and none is special: one pass over every row
        # beats gathers (below _WHOLE_MAX rows a pass costs what a gather does).
        whole = self._plain and (4 * len(moved) >= high or high <= _WHOLE_MAX)
        if len(moved) and not (whole and self.geometry.refresh_all(high, store)):
            self.geometry.refresh(moved, store)
        return len(moved)

    def _relayout(self) -> None:
        """Rows were added, removed or changed mode: register the new ones, cache row sets."""
        store, geo = self._sim.state, self.geometry
        high = store.high_water
        geo.reserve(store.capacity)
        if len(self._start) < store.capacity:
            grown = np.zeros((store.capacity, 3))
            grown[: len(self._start)] = self._start
            self._start = grown
        live = store.active[:high]
        mode = store.collision_mode[:high]
        stale = (
            live
            & (mode != _DISABLED)
            & ((geo.owner[:high] != store.object_id[:high]) | (geo.mode[:high] != mode))
        )
        new_rows = stale.nonzero()[0]
        if len(new_rows):
            geo.register(new_rows, store)
            self._start[new_rows] = store.position[new_rows]
        geo.mode[:high] = np.where(live, mode, geo.mode[:high])
        part = live & (mode != _DISABLED)
        self._rows = part.nonzero()[0]
        self._all_rows = len(self._rows) == high
        modes = mode[self._rows]
        flat, static = modes == _FLAT, modes == _STATIC
        self._flat = flat if np.count_nonzero(flat) else None
        self._static = static if np.count_nonzero(static) else None
        self._unstatic = None  # (rows that are not static, their NORMAL_2D mask or None)
        if self._static is not None:
            moving = ~static
            mflat = flat[moving]
            self._unstatic = (self._rows[moving], mflat if np.count_nonzero(mflat) else None)
        self._plain = self._static is None and not np.count_nonzero(geo.articulated[self._rows])
        self._layout = store.layout_version

    def bounds(self, rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """(min, max) corners of the union of the (unpadded) AABBs of ``rows`` (default: all
        taking part) that have one; None when none has."""
        self._prepare()
        rows = self._rows if rows is None else rows[np.isin(rows, self._rows)]
        if not len(rows):
            return None
        lo, hi = self.geometry.unpadded(rows)
        return lo.min(axis=0), hi.max(axis=0)

    def get_aabbs(self) -> dict[int, tuple[list[float], list[float]]]:
        """``{object_id: (aabb_min, aabb_max)}`` for every object that takes part."""
        self._prepare()
        rows = self._rows
        ids = self._sim.state.object_id[rows].tolist()
        lo, hi = self.geometry.unpadded(rows)
        return dict(zip(ids, zip(lo.tolist(), hi.tolist(), strict=True), strict=True))

    # ----- broad phase --------------------------------------------------------------------

    def resolve_cell_size(self, rows: np.ndarray, recompute: bool = False) -> float:
        """The hash cell size in force, computing it per the cell size mode when needed."""
        if self.cell_mode is SpatialHashCellSizeMode.CONSTANT and self.cell_size:
            return self.cell_size
        adaptive = self.cell_mode is SpatialHashCellSizeMode.AUTO_ADAPTIVE
        if self.cell_size is None or recompute or adaptive:
            lo, hi = self.geometry.unpadded(rows)
            self.cell_size = auto_cell_size(lo, hi)
        return self.cell_size

    def filter_pairs(
        self, ignore_static: bool | None = None, moved_ids: set[int] | None = None
    ) -> tuple[np.ndarray, dict[str, float]]:
        """Row pairs (i < j) whose AABBs overlap (inflated by the margin), with timings in ms."""
        t0 = time.perf_counter()
        n_moved = self._prepare()
        t1 = time.perf_counter()
        store = self._sim.state
        if moved_ids is not None:
            ids = np.fromiter(moved_ids, dtype=np.int64, count=len(moved_ids))
            pairs = self._broad_phase(np.isin(store.object_id[self._rows], ids), ignore_static)
        elif n_moved:
            pairs = self._broad_phase(None, ignore_static)
        else:
            pairs = _NO_PAIRS
        t2 = time.perf_counter()
        if len(pairs):
            pairs = pairs[self.narrow.aabbs_overlap(pairs)]
        t3 = time.perf_counter()
        return pairs, {
            "get_aabbs": (t1 - t0) * 1e3,
            "spatial_hashing": (t2 - t1) * 1e3,
            "aabb_filtering": (t3 - t2) * 1e3,
        }

    def _broad_phase(
        self, moved: np.ndarray | None, ignore_static: bool | None, sweep: bool = False
    ) -> np.ndarray:
        """Candidate row pairs (sharing a hash cell, one side moved, static rules applied);
        ``moved`` None: the store's flags. Their AABBs may not overlap."""
        store, geo = self._sim.state, self.geometry
        rows, flat, all_rows = self._rows, self._flat, self._all_rows
        skip_static = self.ignore_static if ignore_static is None else ignore_static
        if skip_static and self._unstatic is not None and self._static is not None:
            # Every pair with a static row is left out, so static rows (a map's tile bodies,
            # big enough to be paired with every object) are not hashed at all.
            rows, flat = self._unstatic
            all_rows = False
            if moved is not None:
                moved = moved[~self._static]
        high = store.high_water
        boxes = geo.aabb[:, :high] if all_rows else geo.aabb.take(rows, axis=1)
        if moved is None:
            moved = store.moved[:high] if all_rows else store.moved[rows]
        amin, amax = boxes[0], boxes[1]
        side_by_side: np.ndarray | None = boxes
        threshold = self.multi_cell_threshold
        if sweep:
            shift = self._start[rows] - store.position[rows]
            amin = amin + np.minimum(shift, 0.0)
            amax = amax + np.maximum(shift, 0.0)
            side_by_side = None  # shifted copies
            # A swept box spans a few more cells than the box: hash it over them rather
            # than test it against every object; only a jump of many cells (a teleport) is
            # tested that way.
            threshold = max(threshold, _SWEPT_CELLS)
        cell = self.resolve_cell_size(rows)
        idx = candidate_pairs(amin, amax, flat, moved, cell, threshold, side_by_side, self._kernel)
        # (Not skipping static rows, static-static pairs are checked too, once: they never move.)
        if not len(idx):
            return _NO_PAIRS
        return idx if all_rows else rows[idx]

    # ----- checks -------------------------------------------------------------------------

    def run(self) -> None:
        """The step's check: like :meth:`check`, without building its return value."""
        if self._prepare():
            self._finish(self._broad_phase(None, None, self.sweep), None, False)
        elif self._relaid and len(self._active):
            self._finish(_NO_PAIRS, None, True)  # contacts of removed objects end
        # else nothing moved and nobody left: no pair can have started or ended
        self._relaid = False

    def check(
        self, ignore_static: bool | None = None, collision_color: list[float] | None = None
    ) -> tuple[list[tuple[int, int]], dict[str, float]]:
        """Run one check; return the active pairs (object ids, i < j) and timings in ms
        (``get_aabbs``, ``spatial_hashing``, ``aabb_filtering``, ``contact_points``, ``events``:
        the collision events' handlers, ``total``)."""
        t0 = time.perf_counter()
        if self.sweep:
            row_pairs = (
                self._broad_phase(None, ignore_static, True) if self._prepare() else _NO_PAIRS
            )
            timings = {"get_aabbs": 0.0, "spatial_hashing": 0.0, "aabb_filtering": 0.0}
            checked = False
        else:
            row_pairs, timings = self.filter_pairs(ignore_static)
            checked = True
        t1 = time.perf_counter()
        events_ms = self._finish(row_pairs, collision_color, checked)
        self._relaid = False
        timings["contact_points"] = (time.perf_counter() - t1) * 1e3 - events_ms
        timings["events"] = events_ms
        timings["total"] = (time.perf_counter() - t0) * 1e3
        return self._active.as_list(), timings

    def _finish(
        self,
        row_pairs: np.ndarray,
        color: list[float] | None,
        aabb_checked: bool,
    ) -> float:
        """Narrow phase on the candidates, active pair update, events; clear ``moved``.
        Return the ms the events took."""
        store = self._sim.state
        touching = self.narrow.touching(row_pairs, store, aabb_checked=aabb_checked)
        if self.sweep and np.count_nonzero(touching) < touching.size:
            self._sweep_test(row_pairs, touching)
        ended, started = self._active.update(row_pairs.compress(touching, axis=0), store)
        if self.sweep:
            moved_rows = store.moved[: store.high_water].nonzero()[0]
            self._start[moved_rows] = store.position[moved_rows]
        store.moved[: store.high_water] = False
        if not (len(ended) or len(started)):
            return 0.0
        t0 = time.perf_counter()
        self._emit(ended, started, color)
        return (time.perf_counter() - t0) * 1e3

    def _sweep_test(self, row_pairs: np.ndarray, touching: np.ndarray) -> None:
        """Mark pairs that touched on the way (were not in contact before, are not now)."""
        store, geo = self._sim.state, self.geometry
        apart = (~touching).nonzero()[0]
        apart = apart[~self._active.contains(pair_codes(store.object_id[row_pairs[apart]]))]
        if not len(apart):
            return
        rp = row_pairs[apart]
        shift = self._start[rp] - store.position[rp]  # (K, 2, 3)
        lo = geo.aabb_min[rp] + np.minimum(shift, 0.0)
        hi = geo.aabb_max[rp] + np.maximum(shift, 0.0)
        sep = (lo[:, 0] > hi[:, 1]) | (lo[:, 1] > hi[:, 0])
        flat = geo.mode[rp] == _FLAT
        sep[:, 2] &= ~(flat[:, 0] | flat[:, 1])
        apart = apart[~sep.any(axis=1)]  # swept AABBs overlap
        if len(apart):
            touching[apart] = self.narrow.touched_during(row_pairs[apart], store, self._start)

    def _emit(self, ended: np.ndarray, started: np.ndarray, color: list[float] | None) -> None:
        sim = self._sim
        if len(started):
            sim.note_collisions(len(started))
        events = sim.events
        listened = (
            events.has_handlers(SimEvents.COLLISION_ENDED)
            or events.has_handlers(SimEvents.COLLISION_STARTED)
            or sim.world.has_entity_buses
        )
        if listened:
            for event, codes in (
                (SimEvents.COLLISION_ENDED, ended),
                (SimEvents.COLLISION_STARTED, started),
            ):
                for a_id, b_id in decode(codes):
                    obj_a, obj_b = sim.get_object_by_id(a_id), sim.get_object_by_id(b_id)
                    events.emit(event, sim=sim, obj_a=obj_a, obj_b=obj_b)
                    for me, other in ((obj_a, obj_b), (obj_b, obj_a)):
                        if me is not None and me.has_event_bus():
                            me.events.emit(event, sim=sim, obj_a=obj_a, obj_b=obj_b, other=other)
        if self.listeners:  # one call per check, arrays decoded without a loop over pairs
            ended_ids, started_ids = id_pairs(ended), id_pairs(started)
            for listener in tuple(self.listeners):
                listener(ended_ids, started_ids)
        if self.color_change:
            self._recolor(color if color is not None else sim.collision_color)

    def _recolor(self, color: list[float]) -> None:
        sim = self._sim
        colliding = {i for pair in self._active.as_list() for i in pair}
        for object_id in colliding - set(self._colors):
            obj = sim.get_object_by_id(object_id)
            if obj is None or obj.body_id < 0:
                continue
            data = p.getVisualShapeData(obj.body_id, physicsClientId=sim.client)
            self._colors[object_id] = [(d[1], d[7]) for d in data]
            for link, _ in self._colors[object_id]:
                p.changeVisualShape(obj.body_id, link, rgbaColor=color, physicsClientId=sim.client)
        for object_id in set(self._colors) - colliding:
            saved = self._colors.pop(object_id)
            obj = sim.get_object_by_id(object_id)
            if obj is not None:
                for link, rgba in saved:
                    p.changeVisualShape(
                        obj.body_id, link, rgbaColor=list(rgba), physicsClientId=sim.client
                    )

    def active_pairs(self) -> list[tuple[int, int]]:
        """Active pairs (object ids, i < j), sorted."""
        return self._active.as_list()
