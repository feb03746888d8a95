"""FieldTable: the agents with safety fields, their parameters and stop state, as arrays.

One entry per agent with fields, kept in arrays indexed by the entry's place (rebuilt when an
agent gains or loses its fields, carrying each agent's state over). ``safety.py`` runs the
phase on it; this module knows nothing of the broad phase.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from fleet_async.core.base.events import SimEvents
from fleet_async.core.collision.safety_geometry import FieldShapes, heading_columns
from fleet_async.core.collision.safety_params import SafetyFieldParams

if TYPE_CHECKING:
    from fleet_async.core.collision.system import CollisionSystem
    from fleet_async.core.world.state import KinematicState
    from fleet_async.core.world.world import World

__all__ = ["FieldTable"]

_MOVING = 1e-6  # m/s: slower than this a robot has no direction of travel
_CLEARANCE = 0.02  # m above the robot's lowest point where its fields begin
_MIN_RAMP_SPEED = 0.05  # m/s: a slower plan ramps its time scale as if it drove at this
_NO_AABB_HEIGHT = 1.0  # m: the field's height for a robot without collision geometry
_NO_SEGMENTS = np.zeros((0, 2))

Emit = Callable[..., None]


class _Entry:
    __slots__ = ("agent", "dir", "held", "params", "since", "speed", "steps", "stops")

    def __init__(self, agent: Any, params: SafetyFieldParams) -> None:
        self.agent = agent
        self.params = params
        self.held = False
        self.speed = 0.0
        self.dir = (1.0, 0.0)
        self.since = 0
        self.stops = 0
        self.steps = 0


class FieldTable:
    """The field agents of one simulation and their state.

    Args:
        store: The simulation's state store.
    """

    def __init__(self, store: KinematicState) -> None:
        self._store = store
        self._entries: dict[int, _Entry] = {}
        self._retired: dict[int, tuple[int, int]] = {}  # removed agents' (stops, steps)
        self._stale = True
        self._shapes: FieldShapes | None = None
        self._active = np.zeros(0, dtype=bool)
        self.had_scale = False
        """Whether the last step held or slowed someone (so the next must reset the scale)."""
        self.kernels: tuple[Callable[..., Any], Callable[..., Any]] | None = None
        """``check_jit.field_speeds`` and ``field_frames``, when numba is used."""
        self.frame: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        """The last :meth:`shapes`' field columns and warning bounds, from the kernels."""
        self._build([])

    def __len__(self) -> int:
        return len(self._entries)

    # ----- membership ---------------------------------------------------------------------

    def add(self, agent: Any, params: SafetyFieldParams) -> None:
        self._save()
        old = self._entries.get(agent.object_id)
        entry = _Entry(agent, params)
        if old is not None:
            entry.stops, entry.steps = old.stops, old.steps
        self._entries[agent.object_id] = entry
        self._stale = True

    def remove(self, object_id: int) -> int | None:
        """Drop an agent's entry; return its row, or None if it had none."""
        self._save()
        entry = self._entries.pop(object_id, None)
        if entry is None:
            return None
        self._retired[object_id] = (entry.stops, entry.steps)
        self._stale = True
        return int(entry.agent.state_row)

    def clear(self) -> None:
        self._entries.clear()
        self._retired.clear()
        self._stale = True
        self.had_scale = False

    def prune(self, world: World) -> None:
        """Drop the entries of agents no longer in ``world`` (removed ones)."""
        for oid, entry in list(self._entries.items()):
            if world.get(oid) is not entry.agent:
                self.remove(oid)

    def params_of(self, object_id: int) -> SafetyFieldParams | None:
        entry = self._entries.get(object_id)
        return None if entry is None else entry.params

    def is_held(self, object_id: int) -> bool:
        i = self._index.get(object_id)
        return bool(self.held[i]) if i is not None and not self._stale else False

    def held_agents(self) -> list[Any]:
        if self._stale:
            return []
        return [self._agents[i] for i in self.held.nonzero()[0].tolist()]

    @property
    def held_count(self) -> int:
        return 0 if self._stale else int(np.count_nonzero(self.held))

    def stats(self) -> dict[int, tuple[int, int]]:
        """``{object_id: (stops, steps stopped)}``, removed agents included."""
        self._save()
        out = dict(self._retired)
        out.update({oid: (e.stops, e.steps) for oid, e in self._entries.items()})
        return dict(sorted(out.items()))

    # ----- arrays -------------------------------------------------------------------------

    def _save(self) -> None:
        """Write the arrays' per-agent state back to the entries (before a rebuild)."""
        if self._stale:
            return
        for i, agent in enumerate(self._agents):
            entry = self._entries.get(agent.object_id)
            if entry is not None:
                entry.held = bool(self.held[i])
                entry.speed = float(self.held_speed[i])
                entry.dir = (float(self.held_dir[i, 0]), float(self.held_dir[i, 1]))
                entry.since = int(self.since[i])
                entry.stops = int(self.stops[i])
                entry.steps = int(self.steps[i])

    def _build(self, entries: list[_Entry]) -> None:
        self._agents = [e.agent for e in entries]
        self._index = {a.object_id: i for i, a in enumerate(self._agents)}
        self.rows = np.array([a.state_row for a in self._agents], dtype=np.int64)
        self._row_index = {int(r): i for i, r in enumerate(self.rows.tolist())}
        prm = [e.params for e in entries]

        def col(name: str) -> np.ndarray:
            return np.array([getattr(p, name) for p in prm], dtype=float)

        self.decel, self.margin_p = col("deceleration"), col("protective_margin")
        self.margin_w, self.side = col("warning_margin"), col("side_margin")
        self.slow = col("slow_factor")
        fp = [p.footprint if p.footprint is not None else (np.nan, np.nan) for p in prm]
        self.half = 0.5 * np.array(fp, dtype=float).reshape(-1, 2)
        self.z_off = np.tile([0.0, _NO_AABB_HEIGHT], (len(prm), 1))
        self.resolved = np.array([p.footprint is not None for p in prm], dtype=bool)
        self.held = np.array([e.held for e in entries], dtype=bool)
        self.held_speed = np.array([e.speed for e in entries], dtype=float)
        self.held_dir = np.array([e.dir for e in entries], dtype=float).reshape(-1, 2)
        self.since = np.array([e.since for e in entries], dtype=np.int64)
        self.stops = np.array([e.stops for e in entries], dtype=np.int64)
        self.steps = np.array([e.steps for e in entries], dtype=np.int64)
        self.last_scale = np.ones(len(prm))
        self.protective_depth = np.zeros(len(prm))
        self.warning_depth = np.zeros(len(prm))
        self._blockers: dict[int, set[int]] = {}
        self._shapes = None
        self._active = np.zeros(len(prm), dtype=bool)
        self.speed = np.zeros(len(prm))
        self._z_known = np.zeros(len(prm), dtype=bool)
        self._memo: dict[str, tuple[tuple[np.ndarray, ...], Any]] = {}

    def sync(self, collision: CollisionSystem) -> None:
        """Rebuild after membership changes; take footprints and heights from collision boxes."""
        if self._stale:
            self._build(list(self._entries.values()))
            self._stale = False
        todo = (~self._z_known).nonzero()[0]
        if not len(todo):
            return
        part = collision.prepare_rows()
        rows = self.rows[todo]
        has = np.isin(rows, part)
        if np.count_nonzero(has):
            idx, r = todo[has], rows[has]
            lo, hi = collision.geometry.unpadded(r)
            pos = self._store.position[r]
            self.z_off[idx, 0] = lo[:, 2] - pos[:, 2]
            self.z_off[idx, 1] = hi[:, 2] - pos[:, 2]
            fill = idx[~self.resolved[idx]]
            sel = ~self.resolved[idx]
            self.half[fill] = 0.5 * (hi[sel, :2] - lo[sel, :2])
        self.half[np.isnan(self.half)] = 0.0
        self.resolved[:] = True
        self._z_known[todo] = True

    def z_band(self, owners: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(bottom, top) (m) of the fields of entries ``owners`` (None: every entry)."""
        if owners is None:
            z = self._store.position[:, 2][self.rows]
            return z + self.z_off[:, 0] + _CLEARANCE, z + self.z_off[:, 1]
        z = self._store.position[:, 2][self.rows[owners]]
        return z + self.z_off[owners, 0] + _CLEARANCE, z + self.z_off[owners, 1]

    def shapes(
        self, on_path: np.ndarray, segments: Callable[[], tuple[np.ndarray, np.ndarray]]
    ) -> tuple[FieldShapes, np.ndarray]:
        """This step's field shapes and which entries have a field in force.

        Args:
            on_path: (capacity,) whether each store row follows a path.
            segments: Returns (store rows, (K, 2) unit directions) of the rows whose current
                path segment moves them (others stand or turn in place); asked only when
                some robot with fields stands.
        """
        if self.kernels is not None:
            return self._shapes_compiled(on_path, segments)
        self.frame = None
        store, rows, held = self._store, self.rows, self.held
        vx, vy = store.velocity[:, 0][rows], store.velocity[:, 1][rows]
        speed = self._cache("speed", (vx, vy), lambda c: np.hypot(c[0], c[1]))
        moving = speed > _MOVING
        # Where a robot drives: along its velocity; standing (stopped, or about to start a
        # segment), along the segment it is to drive (a new path turns a stopped robot's
        # fields with it); else the way it was going when it stopped.
        if np.count_nonzero(moving) < len(moving):
            seg_rows, seg_dirs = segments()
            seg = np.zeros((store.capacity, 2))
            seg[seg_rows] = seg_dirs
            sx, sy = seg[:, 0][rows], seg[:, 1][rows]
            has_seg = (sx != 0.0) | (sy != 0.0)
        else:  # everyone drives: the segments decide nothing
            sx = sy = np.zeros(len(rows))
            has_seg = np.zeros(len(rows), dtype=bool)
        active = on_path[rows] & (moving | held | has_seg)
        divisor = np.where(moving, speed, 1.0)
        tx = np.where(moving, vx / divisor, np.where(has_seg, sx, self.held_dir[:, 0]))
        ty = np.where(moving, vy / divisor, np.where(has_seg, sy, self.held_dir[:, 1]))
        idle = ~(moving | held | has_seg)
        tx[idle], ty[idle] = 1.0, 0.0
        # The speed the robot's path is planned at (its actual speed undoes last step's scale;
        # a stopped robot resumes at the speed it stopped at), and the speed it drives at now,
        # which sizes the fields: a stopped robot's fields are their standstill depth.
        last = self.last_scale
        self.speed = np.where(held, self.held_speed, speed / np.where(last > 0, last, 1.0))
        self.protective_depth = speed * speed / (2.0 * self.decel) + self.margin_p
        self.warning_depth = self.protective_depth + self.margin_w
        quat = tuple(store.orientation[:, k][rows] for k in range(4))
        hx, hy = self._cache("heading", quat, heading_columns)
        pos = store.position
        shapes = FieldShapes(
            (pos[:, 0][rows], pos[:, 1][rows]),
            (hx, hy),
            (tx, ty),
            self.half[:, 0],
            self.half[:, 1],
            self.side,
        )
        self._shapes, self._active = shapes, active
        return shapes, active

    def _shapes_compiled(
        self, on_path: np.ndarray, segments: Callable[[], tuple[np.ndarray, np.ndarray]]
    ) -> tuple[FieldShapes, np.ndarray]:
        """:meth:`shapes` as ``check_jit``'s kernels, which also lay out the field columns and
        the warning fields' bounds (``frame``); the same values bit for bit."""
        assert self.kernels is not None
        speeds, frames = self.kernels
        store, rows, m = self._store, self.rows, len(self.rows)
        speed = np.empty(m)
        seg = _NO_SEGMENTS
        if speeds(rows, store.velocity, _MOVING, speed):  # some stand: their segments decide
            seg_rows, seg_dirs = segments()
            seg = np.zeros((store.capacity, 2))
            seg[seg_rows] = seg_dirs
        shape, depths = np.empty((8, m)), np.empty((3, m))
        active, fields = np.empty(m, dtype=bool), np.empty((21, m))
        lo, hi = np.empty((m, 3)), np.empty((m, 3))
        frames(
            rows,
            (store.velocity, store.orientation, store.position, on_path),
            seg,
            (self.held, self.held_dir, self.held_speed, self.last_scale),
            (self.decel, self.margin_p, self.margin_w, self.half, self.side, self.z_off),
            (_MOVING, _CLEARANCE),
            speed,
            (shape, depths, active, fields, lo, hi),
        )
        self.speed, self.protective_depth, self.warning_depth = depths
        shapes = FieldShapes.of_columns(shape)
        self._shapes, self._active, self.frame = shapes, active, (fields, lo, hi)
        return shapes, active

    def _cache(self, name: str, inputs: tuple[np.ndarray, ...], fn: Callable[[Any], Any]) -> Any:
        """``fn(inputs)`` (arrays of one value per entry), recomputed only for the entries whose
        inputs changed since the last step (the same values: ``fn`` works entry by entry)."""
        old = self._memo.get(name)
        if old is not None and len(old[0][0]) == len(inputs[0]):
            changed = np.zeros(len(inputs[0]), dtype=bool)
            for a, b in zip(inputs, old[0], strict=True):
                changed |= a != b
            if not np.count_nonzero(changed):
                return old[1]
            idx = changed.nonzero()[0]
            fresh = fn(tuple(a[idx] for a in inputs))
            out = old[1]
            if isinstance(out, tuple):
                out = tuple(o.copy() for o in out)
                for o, f in zip(out, fresh, strict=True):
                    o[idx] = f
            else:
                out = out.copy()
                out[idx] = fresh
        else:
            out = fn(inputs)
        self._memo[name] = (inputs, out)
        return out

    def not_carried(self, owner: np.ndarray, obstacle_row: np.ndarray, world: World) -> np.ndarray:
        """Mask of pairs whose obstacle is not carried by (attached below) the field's owner."""
        keep = np.ones(len(owner), dtype=bool)
        if not len(world.attachments) or not len(owner):
            return keep
        parents = world.attachments.parent_ids()
        for i in np.unique(owner).tolist():
            agent = self._agents[i]
            if agent.object_id in parents:
                carried = [d.state_row for d in world.attachments.descendants(agent)]
                keep &= ~((owner == i) & np.isin(obstacle_row, carried))
        return keep

    # ----- the outcome --------------------------------------------------------------------

    def settle(
        self,
        active: np.ndarray,
        hits: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None,
        step: int,
        emit: Emit,
        dt: float,
        objects: Callable[[list[int]], list[Any]],
    ) -> np.ndarray | None:
        """Hold, slow or release every entry; emit stops and ends; return the time scale by
        store row (None: nobody held or slowed)."""
        m = len(self.rows)
        prot_any = np.zeros(m, dtype=bool)
        warn_any = np.zeros(m, dtype=bool)
        self._blockers = {}
        if hits is not None:
            owner, obstacle_row, prot, warn = hits
            prot_any[owner[prot]] = True
            warn_any[owner[warn]] = True
            for i, r in zip(owner[prot].tolist(), obstacle_row[prot].tolist(), strict=True):
                self._blockers.setdefault(i, set()).add(r)
        held_now = active & prot_any
        started = (held_now & ~self.held).nonzero()[0]
        ended = (self.held & ~held_now).nonzero()[0]
        if len(started):
            self.held_speed[started] = self.speed[started]
            self.held_dir[started] = self._shapes.u[started] if self._shapes is not None else 0.0
            self.since[started] = step
            self.stops[started] += 1
        self.held = held_now
        self.steps[held_now] += 1
        for i in ended.tolist():
            duration = (step - int(self.since[i])) * dt
            emit(SimEvents.SAFETY_STOP_ENDED, self._agents[i], duration=duration)
        for i in started.tolist():
            blockers = sorted(r for r in self._blockers.get(i, ()) if r >= 0)
            emit(SimEvents.SAFETY_STOP_STARTED, self._agents[i], obstacles=objects(blockers))
        # Stopping and slowing take effect at once; speeding up again (after a stop or a slow
        # down) ramps the time scale so that the robot accelerates at its ``deceleration``.
        target = np.where(held_now, 0.0, np.where(warn_any & active, self.slow, 1.0))
        last = self.last_scale
        ramp = dt * self.decel / np.maximum(self.speed, _MIN_RAMP_SPEED)
        scale = np.where(target < last, target, np.minimum(target, last + ramp))
        self.last_scale = scale
        if np.all(scale == 1.0):
            self.had_scale = False
            return None
        self.had_scale = True
        out = np.ones(self._store.capacity)
        out[self.rows] = scale
        return out

    def held_by(self) -> dict[int, set[int]]:
        """``{row of a stopped entry: rows of stopped entries in its protective field}``."""
        held_rows = set(self.rows[self.held].tolist())
        return {
            int(self.rows[i]): self._blockers.get(i, set()) & held_rows
            for i in self.held.nonzero()[0].tolist()
        }

    def agents_at(self, rows: list[int]) -> list[Any]:
        return [self._agents[self._row_index[r]] for r in rows]

    # ----- checkpoints ---------------------------------------------------------------------

    def get_state(self) -> dict[str, Any]:
        """Plain data for a checkpoint: each agent's parameters, footprint and stop state (by
        object id, in the order they joined), the removed agents' counts."""
        self._save()
        agents = []
        for oid, e in self._entries.items():
            i = None if self._stale else self._index.get(oid)
            known = i is not None and bool(self._z_known[i])
            params = {f: getattr(e.params, f) for f in SafetyFieldParams.__dataclass_fields__}
            if e.params.footprint is not None:
                params["footprint"] = list(e.params.footprint)
            agents.append(
                {
                    "id": oid,
                    "params": params,
                    "stop": [e.held, e.speed, list(e.dir), e.since, e.stops, e.steps],
                    "scale": 1.0 if i is None else float(self.last_scale[i]),
                    "shape": [*self.half[i].tolist(), *self.z_off[i].tolist()] if known else None,
                }
            )
        retired = [[oid, stops, steps] for oid, (stops, steps) in self._retired.items()]
        return {"agents": agents, "retired": retired, "had_scale": self.had_scale}

    def set_state(self, state: dict[str, Any], agent_of: Callable[[int], Any]) -> None:
        """Take a :meth:`get_state` back (``agent_of`` maps an object id to its agent).

        Raises:
            ValueError: for an id that is no agent, or bad parameters.
        """
        entries = []
        for saved in state["agents"]:
            agent = agent_of(int(saved["id"]))
            if agent is None:
                raise ValueError(f"safety fields: object {saved['id']} is no agent here")
            params = SafetyFieldParams.coerce(saved["params"], "safety_field")
            if params is None:
                raise ValueError(f"safety fields: object {saved['id']} has no parameters")
            entry = _Entry(agent, params)
            held, speed, direction, since, stops, steps = saved["stop"]
            entry.held, entry.speed, entry.dir = bool(held), float(speed), tuple(direction)
            entry.since, entry.stops, entry.steps = int(since), int(stops), int(steps)
            entries.append((entry, saved))
        self._entries = {e.agent.object_id: e for e, _ in entries}
        self._retired = {int(oid): (int(a), int(b)) for oid, a, b in state["retired"]}
        self._build([e for e, _ in entries])
        self._stale = False
        for i, (_, saved) in enumerate(entries):
            self.last_scale[i] = float(saved["scale"])
            if saved["shape"] is not None:
                hx, hy, z0, z1 = (float(v) for v in saved["shape"])
                self.half[i], self.z_off[i] = (hx, hy), (z0, z1)
                self.resolved[i] = self._z_known[i] = True
        self.had_scale = bool(state["had_scale"])

    def corners(self, object_id: int, warning: bool) -> list[tuple[float, float]]:
        i = self._index.get(object_id)
        if i is None or self._stale or self._shapes is None or not self._active[i]:
            return []
        depth = self.warning_depth if warning else self.protective_depth
        return self._shapes.corners(i, float(depth[i]))
