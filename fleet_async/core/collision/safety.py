"""Safety fields for the whole fleet: stop in the protective field, slow in the warning field.

Runs once per step as the ``safety_fields`` phase, just before the motion phase, on the poses
the previous step left. For every agent with fields (``SafetyFieldParams``) that follows a path
and drives or is about to drive a segment (or is stopped by its field), the fields are laid
ahead of its footprint along its direction of travel (its velocity; standing, the segment it
is to drive) and sized by the speed it drives at (``safety_geometry.py``). Which obstacle may
stand in which field (other objects' AABBs, a map's obstacle boxes) comes from a pair list
kept between steps (``safety_join.py``); the listed pairs are then tested exactly (a rectangle
against a box). ``safety_reference.py`` keeps the first, slower evaluation (the collision broad
phase every step), which gives the same results. Per robot:

- something in the protective field: the robot does not move in this step (the engine's time
  scale is 0 for it: its path and profile wait, its action stays active);
  ``safety_stop_started`` is emitted when it begins. A stopped robot's fields have their
  standstill depth, so it creeps up to an obstacle further away than its margin;
- the field clears (or the robot's path ends or is cancelled): ``safety_stop_ended``, and the
  robot drives on from where it stopped, its time scale ramping up so that it speeds up at its
  field's ``deceleration``;
- something in the warning field only: the robot drives at ``slow_factor`` of its speed.

What is not an obstacle: the robot itself, what it carries (its attachments), anything
entirely below 2 cm (``safety_state.py``) above the robot's base or above its top (the floor, a
shelf it drives under). Velocity commands are held and slowed as paths are (the engine scales
them); a custom base controller, which moves its robot itself, is not watched.
Stopped robots that hold each other are watched for deadlocks (``safety_deadlock.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from fleet_async.core.base.compiled import use_numba
from fleet_async.core.base.events import SimEvents
from fleet_async.core.collision.safety_deadlock import DeadlockWatch, blocked_sets
from fleet_async.core.collision.safety_geometry import (
    FieldShapes,
    box_columns,
    field_columns,
    pair_hits,
    warning_bounds,
)
from fleet_async.core.collision.safety_join import AHEAD, FieldPairs
from fleet_async.core.collision.safety_params import SafetyFieldParams
from fleet_async.core.collision.safety_reference import Hits, reference_hits
from fleet_async.core.collision.safety_state import FieldTable

if TYPE_CHECKING:
    from fleet_async.core.collision.system import CollisionSystem
    from fleet_async.core.world.world import World

__all__ = ["FieldMotion", "SafetyFields"]


class FieldMotion(Protocol):
    """What the fields need of the agents' motion (``agents/fleet.py``)."""

    def path_rows(self) -> np.ndarray: ...

    def segment_directions(self) -> tuple[np.ndarray, np.ndarray]: ...

    def set_time_scale(self, scale_of_row: Any) -> None: ...


class SafetyHost(Protocol):
    """The simulation, as the safety fields see it."""

    @property
    def world(self) -> World: ...

    @property
    def events(self) -> Any: ...

    @property
    def step_count(self) -> int: ...

    @property
    def sim_time(self) -> float: ...

    @property
    def params(self) -> Any: ...


class SafetyFields:
    """The safety fields of one simulation (``sim.safety``).

    Args:
        sim: The simulation.
        collision: Its collision system (AABBs and the broad phase's settings).
        motion: The agents' motion (who follows a path; holding and slowing).
    """

    def __init__(self, sim: SafetyHost, collision: CollisionSystem, motion: FieldMotion) -> None:
        self._sim = sim
        self._collision = collision
        self._motion = motion
        self._table = FieldTable(sim.world.store)
        self._watch = DeadlockWatch()
        self._static_lo = np.zeros((0, 3))
        self._static_hi = np.zeros((0, 3))
        self._transparent: set[int] = set()  # object ids the fields ignore (map bodies)
        self._static_version = 0
        self._static_cols: np.ndarray | None = None
        self._own: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._opaque: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # rows, kept
        # check_jit's kernel, when numba is used (base/compiled.py): the same results
        self._pair_hits: Callable[..., tuple[np.ndarray, np.ndarray]] = pair_hits
        if use_numba(sim.params.kernels):
            from fleet_async.core.collision.check_jit import (
                field_frames,
                field_pair_hits,
                field_speeds,
            )

            self._pair_hits = field_pair_hits
            self._table.kernels = (field_speeds, field_frames)
        self._join = FieldPairs()
        self._layout = -1
        self._evaluator = "pairs"
        self.recorder: Callable[..., None] | None = None
        """Called ``recorder(kind, object_id, **data)`` for each stop, end and deadlock (the
        simulation points it at ``sim.trace_event``, so a running trace logs them)."""
        self.recording: Callable[[], bool] = _always
        """Whether the recorder wants events now (the simulation's: whether a trace runs); the
        fields drawn with each stop are only worked out then."""

    # ----- agents -------------------------------------------------------------------------

    def enable(self, agent: Any, params: SafetyFieldParams | dict[str, Any] | bool = True) -> None:
        """Give ``agent`` safety fields (replacing any it has).

        Raises:
            ValueError: for bad parameters, or an agent not in this simulation.
        """
        prm = SafetyFieldParams.coerce(params, "safety_field")
        if self._sim.world.get(agent.object_id) is not agent:
            raise ValueError(f"safety fields: {agent!r} is not in this simulation")
        if prm is None:
            self.disable(agent)
            return
        self._table.add(agent, prm)

    def disable(self, agent: Any) -> bool:
        """Take ``agent``'s fields away (it resumes if stopped); return whether it had some."""
        row = self._table.remove(agent.object_id)
        return row is not None

    def params_of(self, agent: Any) -> SafetyFieldParams | None:
        """``agent``'s field parameters, or None when it has no fields."""
        return self._table.params_of(agent.object_id)

    def is_stopped(self, agent: Any) -> bool:
        """Whether ``agent`` is stopped by its protective field."""
        return self._table.is_held(agent.object_id)

    def stopped_agents(self) -> list[Any]:
        """Agents stopped by their protective fields, in object-id order."""
        return self._table.held_agents()

    def field_violation(self, agent: Any) -> bool:
        """Whether something is in ``agent``'s protective field now (VDA 5050's
        ``safetyState.fieldViolation``)."""
        return self.is_stopped(agent)

    @property
    def enabled(self) -> bool:
        """Whether any agent has fields (otherwise the phase costs nothing)."""
        return len(self._table) > 0

    @property
    def evaluator(self) -> str:
        """How fields are evaluated: ``"pairs"`` (the default: the pair list kept between
        steps, ``safety_join.py``) or ``"reference"`` (the generic broad phase every step,
        ``safety_reference.py``; slow, for tests). Both give the same results."""
        return self._evaluator

    @evaluator.setter
    def evaluator(self, value: str) -> None:
        if value not in ("pairs", "reference"):
            raise ValueError(f"safety evaluator: expected 'pairs' or 'reference', got {value!r}")
        self._evaluator = value

    @property
    def deadlock_after(self) -> float:
        """Seconds a blocked set of robots must last before ``deadlock_suspected`` (10 s)."""
        return self._watch.deadlock_after

    @deadlock_after.setter
    def deadlock_after(self, value: float) -> None:
        self._watch.deadlock_after = value

    @property
    def deadlocks_suspected(self) -> int:
        """``deadlock_suspected`` events so far."""
        return self._watch.count

    def pair_list_stats(self) -> dict[str, int]:
        """The fields' pair list (``safety_join.py``), for benchmarks: ``builds`` (times built
        anew), ``patches`` (steps that joined escaped boxes again), ``pairs`` (listed now)."""
        join = self._join
        return {"builds": join.builds, "patches": join.patches, "pairs": len(join.field)}

    def stats(self) -> dict[int, tuple[int, float]]:
        """``{object_id: (stops, time stopped in s)}`` of every agent that had fields."""
        dt = self._sim.params.timestep
        return {oid: (stops, steps * dt) for oid, (stops, steps) in self._table.stats().items()}

    # ----- static obstacles ---------------------------------------------------------------

    def add_static_boxes(
        self, lo: np.ndarray, hi: np.ndarray, replaces: list[Any] | None = None
    ) -> None:
        """Add obstacle boxes that are not objects' AABBs (a map's occupied cells).

        Args:
            lo, hi: (K, 3) corners (m, world frame).
            replaces: Objects whose own AABBs the fields ignore, as these boxes stand for
                their geometry (a map's merged bodies, whose AABBs cover the whole map).
        """
        lo = np.asarray(lo, dtype=float).reshape(-1, 3)
        hi = np.asarray(hi, dtype=float).reshape(-1, 3)
        if lo.shape != hi.shape:
            raise ValueError(f"add_static_boxes: {lo.shape} minima for {hi.shape} maxima")
        self._static_lo = np.concatenate((self._static_lo, lo))
        self._static_hi = np.concatenate((self._static_hi, hi))
        self._transparent |= {obj.object_id for obj in replaces or ()}
        self._static_version += 1
        self._static_cols = None
        self._opaque = None

    def field_corners(self, agent: Any, warning: bool = False) -> list[tuple[float, float]]:
        """The corners (m, world frame) of ``agent``'s protective (or warning) field now, for
        drawing; [] when it has no field in force (standing, or without fields)."""
        return self._table.corners(agent.object_id, warning)

    # ----- checkpoints --------------------------------------------------------------------

    def get_state(self) -> dict[str, Any]:
        """Plain data for a checkpoint: every agent's fields and stop state, the KPI counters,
        the deadlock watch (static boxes come with the scenario's maps, so are not saved)."""
        store = self._sim.world.store

        def object_id(row: int) -> int:
            return int(store.object_id[row])

        return {"table": self._table.get_state(), "watch": self._watch.get_state(object_id)}

    def set_state(self, state: dict[str, Any]) -> None:
        """Take a :meth:`get_state` back (a checkpoint restored into a fresh simulation).

        Raises:
            ValueError: for an object id that is no agent of this simulation.
        """
        world = self._sim.world

        def agent_of(object_id: int) -> Any:
            obj = world.get(object_id)
            return obj if obj is not None and hasattr(obj, "motion_slot") else None

        def row(object_id: int) -> int:
            obj = agent_of(object_id)
            if obj is None:
                raise ValueError(f"safety fields: object {object_id} is no agent here")
            return int(obj.state_row)

        self._table.set_state(state["table"], agent_of)
        self._watch.set_state(state["watch"], row)
        self._layout = -1

    # ----- the phase ----------------------------------------------------------------------

    def reset(self) -> None:
        """Forget every agent and box (simulation reset)."""
        self._table.clear()
        self._watch.reset()
        self._static_lo = np.zeros((0, 3))
        self._static_hi = np.zeros((0, 3))
        self._transparent.clear()
        self._static_version += 1
        self._static_cols = None
        self._opaque = None
        self._join.invalidate()
        self._motion.set_time_scale(None)

    def run(self) -> None:
        """The ``safety_fields`` phase: evaluate every field, hold and slow robots, emit."""
        table = self._table
        if not len(table) and not table.had_scale:
            return
        store = self._sim.world.store
        if store.layout_version != self._layout:  # an agent with fields may have left
            self._layout = store.layout_version
            table.prune(self._sim.world)
        table.sync(self._collision)
        on_path = np.zeros(store.capacity, dtype=bool)
        on_path[self._motion.path_rows()] = True
        shapes, active = table.shapes(on_path, self._motion.segment_directions)
        hits = self._hits(shapes, active) if np.count_nonzero(active) else None
        scale = table.settle(
            active, hits, self._sim.step_count, self._emit, self._sim.params.timestep, self._objects
        )
        self._motion.set_time_scale(scale)
        if table.held_count >= 2:
            self._watch_deadlocks()
        elif self._watch.watching:  # no blocked set this step: one that forms again starts anew
            self._watch.update((), self._sim.step_count, self._sim.params.timestep)

    def _hits(self, shapes: FieldShapes, active: np.ndarray) -> Hits:
        """Every obstacle in an active field (see ``safety_join.py``)."""
        table, collision, world = self._table, self._collision, self._sim.world
        if self._evaluator == "reference":
            static = (self._static_lo, self._static_hi)
            return reference_hits(
                table, collision, world, static, self._transparent, shapes, active
            )
        store = world.store
        rows = collision.prepare_rows()
        lo, hi = collision.geometry.unpadded(rows) if len(rows) else (np.zeros((0, 3)),) * 2
        if self._transparent:
            if self._opaque is None or self._opaque[0] is not rows:
                keep = ~np.isin(store.object_id[rows], list(self._transparent))
                self._opaque = (rows, keep, rows[keep])
            keep = self._opaque[1]
            rows, lo, hi = self._opaque[2], lo[keep], hi[keep]
        n_obj = len(rows)
        if table.frame is not None:  # the kernels laid the fields out
            fields, field_lo, field_hi = table.frame
        else:
            z_lo, z_hi = table.z_band()
            warn, prot = table.warning_depth, table.protective_depth
            fields = field_columns(shapes, warn, prot, z_lo, z_hi)
            field_lo, field_hi = warning_bounds(fields)  # for the pair list only
        own = self._own_index(rows, table.rows)
        velocity, ahead = store.velocity, AHEAD * self._sim.params.timestep

        def shift(of_rows: np.ndarray) -> np.ndarray:
            return velocity.take(of_rows, axis=0) * ahead

        self._join.update(
            (len(self._static_lo), self._static_version),
            table.rows,
            (field_lo, field_hi),
            rows,
            (lo, hi),
            (self._static_lo, self._static_hi),
            own,
            shift,
        )
        owner, obstacle = self._join.field, self._join.obstacle
        sel = active[owner]
        if np.count_nonzero(sel) < len(sel):
            owner, obstacle = owner[sel], obstacle[sel]
        boxes = box_columns(lo, hi)
        if len(self._static_lo):
            boxes = np.concatenate((boxes, self._static_columns()), axis=1)
        hit, prot = self._pair_hits(fields, boxes, owner, obstacle)
        owner, obstacle = owner[hit], obstacle[hit]
        obstacle_row = np.where(obstacle < n_obj, rows[np.minimum(obstacle, n_obj - 1)], -1)
        keep = table.not_carried(owner, obstacle_row, world)
        if np.count_nonzero(keep) < len(keep):
            owner, obstacle_row, prot = owner[keep], obstacle_row[keep], prot[keep]
        return owner, obstacle_row, prot, np.ones(len(owner), dtype=bool)

    def _own_index(self, rows: np.ndarray, owners: np.ndarray) -> np.ndarray:
        """Each field owner's index among the obstacle ``rows``, -1 for none (cached while
        both arrays stay the same objects: they are replaced, never changed in place)."""
        cached = self._own
        if cached is not None and cached[0] is rows and cached[1] is owners:
            return cached[2]
        n = len(rows)
        at = np.minimum(np.searchsorted(rows, owners), max(n - 1, 0))
        own = np.where(rows[at] == owners, at, -1) if n else np.full(len(at), -1)
        self._own = (rows, owners, own)
        return own

    def _static_columns(self) -> np.ndarray:
        if self._static_cols is None or self._static_cols.shape[1] != len(self._static_lo):
            self._static_cols = box_columns(self._static_lo, self._static_hi)
        return self._static_cols

    def _objects(self, rows: list[int]) -> list[Any]:
        world = self._sim.world
        ids = world.store.object_id[rows].tolist() if rows else []
        return [obj for obj in (world.get(i) for i in ids) if obj is not None]

    def _emit(self, kind: str, agent: Any, **data: Any) -> None:
        sim = self._sim
        if sim.events.has_handlers(kind):
            sim.events.emit(kind, sim=sim, agent=agent, **data)
        if self.recorder is not None and self.recording():
            extra: dict[str, Any] = {}
            if kind == SimEvents.SAFETY_STOP_STARTED:  # the fields that stopped it, to draw
                extra["protective"] = _rounded(self.field_corners(agent))
                extra["warning"] = _rounded(self.field_corners(agent, warning=True))
            self.recorder(kind, agent.object_id, **_plain(data), **extra)

    def _watch_deadlocks(self) -> None:
        sim = self._sim
        sets = blocked_sets(self._table.held_by())
        due = self._watch.update(sets, sim.step_count, sim.params.timestep)
        for members in due:
            robots = self._table.agents_at(sorted(members))
            names = [a.name or f"#{a.object_id}" for a in robots]
            if sim.events.has_handlers(SimEvents.DEADLOCK_SUSPECTED):
                sim.events.emit(
                    SimEvents.DEADLOCK_SUSPECTED, sim=sim, agents=robots, sim_time=sim.sim_time
                )
            if self.recorder is not None and self.recording():
                ids = [a.object_id for a in robots]
                self.recorder(SimEvents.DEADLOCK_SUSPECTED, None, robots=ids, names=names)


def _always() -> bool:
    return True


def _plain(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with objects replaced by their ids (for the trace's JSON event log)."""
    out: dict[str, Any] = {}
    for key, value in data.items():
        if key == "obstacles":
            out[key] = [getattr(o, "object_id", o) for o in value]
        elif key != "sim":
            out[key] = value
    return out


def _rounded(corners: list[tuple[float, float]]) -> list[list[float]]:
    """Field corners as ``[[x, y], ...]`` rounded to mm (a small trace event)."""
    return [[round(float(x), 3), round(float(y), 3)] for x, y in corners]
