"""The world: every object of one simulation, its row in the state store, and attachments.

``MultiRobotSimulationCore`` owns the clock and the step loop; ``World`` owns what is in the
scene. SimObject handles call back into it (``sim.world``) when they write their pose, change
their collision mode or attach another object.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
import pybullet as p

from fleet_async.core.base.events import EventBus, SimEvents
from fleet_async.core.base.types import CollisionMode
from fleet_async.core.world.attachments import AttachmentSet
from fleet_async.core.world.backend import PyBulletBackend
from fleet_async.core.world.callback_queue import CallbackQueue
from fleet_async.core.world.carrying import Carrying
from fleet_async.core.world.pending import (
    PENDING_BODY,
    Deferred,
    PendingBodies,
    PendingBodiesApi,
)
from fleet_async.core.world.state import COLLISION_CODES, KinematicState

if TYPE_CHECKING:
    from fleet_async.core.world.host import KeptOutside, WorldBody

__all__ = ["World"]

logger = logging.getLogger(__name__)

_B = TypeVar("_B", bound="WorldBody")
"""The handle class of the objects held (the kernel's world holds ``SimObject``)."""


class World(Carrying[_B], PendingBodiesApi):
    """Objects, rows and attachments of one simulation.

    Args:
        sim: The owning simulation (handles are bound to it).
        backend: The PyBullet adapter.
        events: The simulation's bus (spawn / removal events).
        physics: Whether bodies with mass > 0 are dynamic.

    Attributes:
        in_step: Set by the simulation while ``step_once`` runs; pose writes then stay in the
            store until a phase needs PyBullet's view.
    """

    def __init__(
        self,
        sim: object,
        backend: PyBulletBackend,
        events: EventBus,
        physics: bool,
    ) -> None:
        self._sim = sim
        self._backend = backend
        self._events = events
        self._physics = physics
        self._store = KinematicState()
        self._attachments = AttachmentSet(self._store, self.link_pose)
        self._objects: dict[int, _B] = {}
        self._agents: dict[int, _B] = {}
        self._updaters: dict[int, _B] = {}
        self._with_callbacks: dict[int, _B] = {}
        self._callback_queue = CallbackQueue()
        self.scan_callbacks = False
        """Check every object's callbacks every step (the reference the callback queue is
        tested against) instead of popping the due ones from the queue."""
        self._update_listeners: dict[int, _B] = {}
        self._dynamic_rows = np.empty(0, dtype=np.int64)
        self._saved_mass: dict[int, float] = {}
        self._next_id = 0
        self._entity_buses = False
        self._pending = PendingBodies()
        self._body_list_stale = False
        self._expected: Deferred | None = None
        self.in_step = False

    @property
    def client(self) -> int:
        """The PyBullet client id, without creating pending bodies first (for spawning code
        that makes shapes and bodies; raw PyBullet calls use ``sim.client``)."""
        return self._backend.client

    @property
    def store(self) -> KinematicState:
        """The state store."""
        return self._store

    @property
    def attachments(self) -> AttachmentSet:
        """Every parent/child attachment."""
        return self._attachments

    @property
    def objects(self) -> list[_B]:
        """Every object, in spawn order."""
        return list(self._objects.values())

    @property
    def agents(self) -> list[_B]:
        """Every agent, in spawn order."""
        return list(self._agents.values())

    @property
    def object_count(self) -> int:
        """Number of objects."""
        return len(self._objects)

    @property
    def agent_count(self) -> int:
        """Number of agents."""
        return len(self._agents)

    @property
    def has_entity_buses(self) -> bool:
        """Whether any object of this simulation has ever had its own event bus (emitters of
        per-object events can skip building payloads while none has)."""
        return self._entity_buses

    def on_event_bus_created(self) -> None:
        """An object of this simulation created its event bus (``obj.events``)."""
        self._entity_buses = True

    def get(self, object_id: int) -> _B | None:
        """The object with ``object_id``, or None."""
        return self._objects.get(object_id)

    def objects_by_id(self) -> Mapping[int, _B]:
        """A read-only live view ``{object_id: object}``."""
        return MappingProxyType(self._objects)

    def updaters(self) -> tuple[_B, ...]:
        """Objects whose class overrides ``update(dt)``, in spawn order."""
        return tuple(self._updaters.values())

    def objects_with_callbacks(self) -> tuple[_B, ...]:
        """Objects with per-object callbacks, in spawn order."""
        return tuple(self._with_callbacks.values())

    def read_back_dynamic(self) -> None:
        """After a physics step, copy the poses of dynamic bodies into the store."""
        if len(self._dynamic_rows):
            self._backend.read_back(self._store, self._dynamic_rows)

    def _registries(self) -> tuple[dict[int, Any], ...]:
        """Every object-id index of the world (an object is in some of them)."""
        return (
            self._objects,
            self._agents,
            self._updaters,
            self._with_callbacks,
            self._update_listeners,
        )

    def clear(self) -> list[_B]:
        """Unbind and forget every object (the PyBullet world is reset by the caller)."""
        removed = list(self._objects.values())
        for obj in removed:
            obj.unbind()
        for registry in self._registries():
            registry.clear()
        self._callback_queue.clear()
        self._attachments.clear()
        self._pending.clear()
        self._body_list_stale = False
        self._saved_mass.clear()
        self._dynamic_rows = np.empty(0, dtype=np.int64)
        self._store.clear()
        return removed

    def add(self, obj: _B, notify: bool = True) -> None:
        """Register ``obj`` (``SimObject.__init__`` does this when given ``sim_core``).

        Raises:
            ValueError: if ``obj`` already belongs to this or another simulation.
        """
        if obj.sim_core is not None or obj.object_id >= 0:
            owner = "this" if obj.sim_core is self._sim else "another"
            raise ValueError(f"add_object: {obj!r} already belongs to {owner} simulation")
        body = obj.raw_body_id
        solo = obj.standalone_state
        pos: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0)
        orn: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0, 1.0)
        pending = None
        if body == PENDING_BODY:
            if self._expected is None:
                raise ValueError(f"add_object: {obj!r} has a pending body nobody described")
            pending, pos, orn = self._expected
            self._expected = None
        elif body >= 0 and not (solo is not None and solo.pose_written):
            pos, orn = self._backend.read_pose(body)
        elif obj.state_row >= 0:  # the pose it kept outside a simulation
            pose = obj.get_pose()
            pos, orn = pose.position, pose.orientation
        # Dynamics move a body only if PyBullet gives its base a mass.
        dynamic = self._physics and body >= 0 and self._backend.body_mass(body) > 0
        object_id = self._next_id
        self._next_id += 1
        row = self._store.allocate(
            object_id,
            body,
            pos,
            orn,
            kinematic=not dynamic,
            collision_code=COLLISION_CODES[obj.collision_mode.value],
        )
        obj.bind(self._sim, self._store, row, object_id)
        self._objects[object_id] = obj
        if obj.is_agent:
            self._agents[object_id] = obj
        if obj.overrides_update():
            self._updaters[object_id] = obj
        if obj.has_callbacks():
            self._with_callbacks[object_id] = obj
            self._callback_queue.changed(obj)
        if obj.has_event_bus():
            self._entity_buses = True
            self.on_entity_handlers_changed(obj)
        if dynamic:
            self._dynamic_rows = np.append(self._dynamic_rows, row)
        if pending is not None:
            self._pending.add(pending, row, obj)
        if obj.collision_mode is CollisionMode.DISABLED and body >= 0:
            p.setCollisionFilterGroupMask(body, -1, 0, 0, physicsClientId=self._backend.client)
        if solo is not None:
            self._adopt_standalone(obj, solo, row)
        if notify:
            self.announce(obj)

    def _adopt_standalone(self, obj: _B, solo: KeptOutside, row: int) -> None:
        """Bring in what ``obj`` kept outside a simulation: its pose, reaching this client's
        PyBullet, and attachments to objects already here (the others wait on their end)."""
        if solo.pose_written:
            self._store.dirty[row] = True
            if not self.in_step:
                self._backend.push_rows(self._store, np.array([row]))
        for record in list(solo.links):
            other = record.child if record.parent is obj else record.parent
            if other.sim_core is self._sim:
                solo.forget(record)
                self.attach(record.parent, record.child, record.link_index, record.relative, False)

    def announce(self, obj: _B) -> None:
        """Emit the spawn events of ``obj`` (``add`` does it unless told not to)."""
        self._events.emit(SimEvents.OBJECT_SPAWNED, sim=self._sim, obj=obj)
        if obj.spawned_event is not None:
            self._events.emit(obj.spawned_event, sim=self._sim, agent=obj)
        if obj.has_event_bus():
            obj.events.emit(SimEvents.OBJECT_SPAWNED, sim=self._sim, obj=obj)

    def remove(self, obj: _B) -> None:
        """Remove ``obj`` from the simulation and PyBullet; its children are detached in place.

        Raises:
            ValueError: if ``obj`` is not part of this simulation.
        """
        if obj.sim_core is not self._sim or self._objects.get(obj.object_id) is not obj:
            raise ValueError(f"remove_object: {obj!r} is not part of this simulation")
        parent = obj.get_attached_parent()
        if parent is not None:
            self.detach(parent, obj, None, None)
        for child in obj.get_attached_objects():
            self.detach(obj, child, None, None)
        obj.on_removed()
        object_id, row = obj.object_id, obj.state_row
        for registry in self._registries():
            registry.pop(object_id, None)
        self._dynamic_rows = self._dynamic_rows[self._dynamic_rows != row]
        if obj.raw_body_id == PENDING_BODY:
            self._pending.discard(row)
        else:
            self._backend.remove_body(obj.raw_body_id)
        try:
            # Handlers still see the object's id and last pose.
            self._events.emit(SimEvents.OBJECT_REMOVED, sim=self._sim, obj=obj)
            if obj.removed_event is not None:
                self._events.emit(obj.removed_event, sim=self._sim, agent=obj)
            if obj.has_event_bus():
                obj.events.emit(SimEvents.OBJECT_REMOVED, sim=self._sim, obj=obj)
        finally:
            obj.unbind()
            self._store.release(row)

    def set_poses(
        self,
        object_ids: Sequence[int],
        positions: np.ndarray,
        orientations: np.ndarray,
        *,
        preserve_velocity: bool = True,
    ) -> None:
        """Set the poses of N objects in one call (arrays of shape (N, 3) and (N, 4)).

        Raises:
            ValueError: on shape mismatch, non-finite values or a zero quaternion.
            KeyError: for an object id that is not registered.
        """
        rows = self._rows_of(object_ids)
        pos = np.asarray(positions, dtype=float)
        orn = np.asarray(orientations, dtype=float)
        n = len(rows)
        if pos.shape != (n, 3) or orn.shape != (n, 4):
            raise ValueError(
                f"set_poses: expected positions (N, 3) and orientations (N, 4) for N={n}, "
                f"got {pos.shape} and {orn.shape}"
            )
        if not (np.isfinite(pos).all() and np.isfinite(orn).all()):
            raise ValueError("set_poses: positions and orientations must be finite")
        norms = np.linalg.norm(orn, axis=1)
        if (norms < 1e-12).any():
            bad = int(np.flatnonzero(norms < 1e-12)[0])
            raise ValueError(
                f"set_poses: orientation of object {object_ids[bad]} is a zero quaternion"
            )
        store = self._store
        store.position[rows] = pos
        store.orientation[rows] = orn / norms[:, None]
        store.mark_moved(rows)
        # Only objects that carry something, or that PyBullet owns, need per-object work.
        carried: list[int] = []
        if len(self._attachments):
            for object_id in self._attachments.parent_ids().intersection(
                int(i) for i in object_ids
            ):
                parent = self._objects[object_id]
                self._attachments.follow_parent(parent)
                carried += [c.state_row for c in self._attachments.descendants(parent)]
        for row in rows[~store.kinematic[rows]].tolist():
            self._push_dynamic(row, preserve_velocity)
        if not self.in_step:
            self._backend.push_rows(
                store, np.concatenate([rows, np.array(carried, dtype=np.int64)])
            )

    def get_poses(self, object_ids: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """Return (positions (N, 3), orientations (N, 4)) copies for N objects.

        Raises:
            KeyError: for an object id that is not registered.
        """
        rows = self._rows_of(object_ids)
        return self._store.position[rows].copy(), self._store.orientation[rows].copy()

    def _rows_of(self, object_ids: Sequence[int]) -> np.ndarray:
        try:
            return np.array([self._objects[int(i)].state_row for i in object_ids], dtype=np.int64)
        except KeyError as exc:
            raise KeyError(
                f"object id {exc.args[0]} is not registered in this simulation"
            ) from None

    # ----- hooks called by SimObject handles ----------------------------------------------

    def on_pose_written(self, obj: _B, preserve_velocity: bool) -> None:
        """A handle changed its row's pose: move its children, sync PyBullet if needed now."""
        self._attachments.follow_parent(obj)
        row = obj.state_row
        if not self._store.kinematic[row]:
            self._push_dynamic(row, preserve_velocity)
        if not self.in_step:
            rows = [row] + [c.state_row for c in self._attachments.descendants(obj)]
            self._backend.push_rows(self._store, np.array(rows, dtype=np.int64))

    def on_collision_mode_changed(self, obj: _B, old: CollisionMode, new: CollisionMode) -> None:
        """Apply a collision mode change to PyBullet's contact filter (a pending body gets
        the filter of its mode when it is created)."""
        if obj.raw_body_id < 0:
            return
        if new is CollisionMode.DISABLED:
            p.setCollisionFilterGroupMask(
                obj.server_body_id, -1, 0, 0, physicsClientId=self._backend.client
            )
        elif old is CollisionMode.DISABLED:
            p.setCollisionFilterGroupMask(
                obj.server_body_id, -1, 1, -1, physicsClientId=self._backend.client
            )

    def on_object_callbacks_changed(self, obj: _B) -> None:
        """Track which objects have per-object callbacks (so steps skip the others)."""
        if obj.has_callbacks():
            self._with_callbacks[obj.object_id] = obj
        else:
            self._with_callbacks.pop(obj.object_id, None)
        self._callback_queue.changed(obj)

    def on_entity_handlers_changed(self, obj: _B) -> None:
        """Track which objects listen to their own PRE_UPDATE / POST_UPDATE (only those pay)."""
        bus = obj.events if obj.has_event_bus() else None
        if bus is not None and (
            bus.has_handlers(SimEvents.PRE_UPDATE) or bus.has_handlers(SimEvents.POST_UPDATE)
        ):
            self._update_listeners[obj.object_id] = obj
        else:
            self._update_listeners.pop(obj.object_id, None)

    def has_updaters(self) -> bool:
        """Whether any object's class overrides ``update(dt)`` (cheaper than ``updaters()``)."""
        return bool(self._updaters)

    def has_object_callbacks(self) -> bool:
        """Whether any object has per-object callbacks."""
        return bool(self._with_callbacks)

    def run_object_callbacks(self, step: int, now: float, dt: float) -> None:
        """Run the per-object callbacks due at step ``step`` (sim time ``now``), objects in
        the order they first registered one (``world/callback_queue.py``)."""
        if not self._with_callbacks:
            return
        if self.scan_callbacks:
            for obj in tuple(self._with_callbacks.values()):
                obj.execute_callbacks(now)
            return
        self._callback_queue.run(self._with_callbacks, step, now, dt)

    def object_callback_steps(self, step: int, dt: float, limit: int) -> int:
        """How many steps from ``step`` on (at most ``limit``) run before a per-object
        callback is due."""
        if not self._with_callbacks:
            return limit
        return self._callback_queue.steps_until_due(self._with_callbacks, step, dt, limit)

    def has_update_listeners(self) -> bool:
        """Whether any object listens to its own PRE_UPDATE / POST_UPDATE."""
        return bool(self._update_listeners)

    def emit_pre_update(self, dt: float) -> list[tuple[_B, np.ndarray]]:
        """PRE_UPDATE on each listening object's bus (``dt``), in object id order; returns
        their poses before the motion phase, for :meth:`emit_post_update`."""
        store, out = self._store, []
        for key in sorted(self._update_listeners):
            obj = self._update_listeners[key]
            row = obj.state_row
            out.append((obj, np.concatenate([store.position[row], store.orientation[row]])))
            obj.events.emit(SimEvents.PRE_UPDATE, sim=self._sim, dt=dt)
        return out

    def emit_post_update(self, dt: float, before: list[tuple[_B, np.ndarray]]) -> None:
        """POST_UPDATE on each listening object's bus (``dt``, ``moved``)."""
        store = self._store
        for obj, pose in before:
            if obj.sim_core is not self._sim:  # removed during the motion phase
                continue
            row = obj.state_row
            now = np.concatenate([store.position[row], store.orientation[row]])
            moved = not np.array_equal(now, pose)
            obj.events.emit(SimEvents.POST_UPDATE, sim=self._sim, dt=dt, moved=moved)

    def _push_dynamic(self, row: int, preserve_velocity: bool) -> None:
        body = int(self._store.body_id[row])
        lin, ang = p.getBaseVelocity(body, physicsClientId=self._backend.client)
        self._backend.push_rows(self._store, np.array([row]))
        if preserve_velocity:
            p.resetBaseVelocity(body, lin, ang, physicsClientId=self._backend.client)
        else:
            p.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=self._backend.client)

    def sync_object(self, obj: _B) -> None:
        """Push ``obj``'s pose to PyBullet now if the store has a newer one."""
        row = obj.state_row
        if self._store.dirty[row]:
            self._backend.push_rows(self._store, np.array([row]))

    def link_pose(self, obj: _B, link_index: int) -> tuple[np.ndarray, np.ndarray]:
        """World (position, orientation) of one link of ``obj``, from PyBullet's kinematics."""
        self.sync_object(obj)
        state = p.getLinkState(
            obj.server_body_id,
            link_index,
            computeForwardKinematics=1,
            physicsClientId=self._backend.client,
        )
        return np.asarray(state[4], dtype=float), np.asarray(state[5], dtype=float)
