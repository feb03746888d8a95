"""SimObject: a handle onto one row of the simulation's state store.

A SimObject owns no pose of its own: ``get_pose`` reads the store, ``set_pose`` writes it and
marks the row dirty. An object created without a simulation keeps a private one-row store and
talks to PyBullet client 0 directly, until ``sim.add_object`` adopts it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
import pybullet as p

from fleet_async.core.base.events import EventBus
from fleet_async.core.base.logging_utils import NamedLazyLogger
from fleet_async.core.base.scheduling import PeriodicSchedule
from fleet_async.core.base.types import CollisionMode, coerce_enum
from fleet_async.core.bodies.constructors import SimObjectConstructors
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.geometry.approach import find_nearest
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.vectors import as_orientation, as_position
from fleet_async.core.world.pending import PENDING_BODY
from fleet_async.core.world.shapes import ShapeParams
from fleet_async.core.world.state import COLLISION_CODES, KinematicState

if TYPE_CHECKING:
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["ShapeParams", "SimObject", "SimObjectSpawnParams"]


class SimObject(SimObjectConstructors):
    """A body in the simulation: robot, pallet, shelf or marker.

    Args:
        body_id: PyBullet body unique id (-1 for a virtual object with no body).
        sim_core: The simulation to join; None keeps the object standalone.
        pickable: Whether pick actions may pick it.
        mass: kg; None reads the body's base mass from PyBullet.
        collision_mode: How it takes part in collision detection.
        name: Human-readable name (duplicates allowed).
        user_data: Free-form metadata.
        register: Join ``sim_core`` now (subclasses pass False and call ``add_object`` once
            their own state is ready).

    Attributes:
        object_id: Unique id assigned by the simulation (-1 while standalone).
        name: Human-readable name.
        body_id: PyBullet body id.
        mass: kg.
        pickable: Whether it can be picked.
        user_data: Free-form metadata.
        sim_core: The simulation it belongs to, or None.
    """

    _spawn_params_cls: ClassVar[type[SimObjectSpawnParams]] = SimObjectSpawnParams
    spawned_event: ClassVar[str | None] = None
    """Extra event the simulation emits when an object of this class spawns (e.g. agents)."""
    removed_event: ClassVar[str | None] = None
    """Extra event the simulation emits when an object of this class is removed."""
    is_agent: ClassVar[bool] = False
    """Whether the simulation lists objects of this class in ``sim.agents``."""
    _store: KinematicState
    _logger: NamedLazyLogger | None = None

    def __init__(
        self,
        body_id: int,
        sim_core: MultiRobotSimulationCore | None = None,
        pickable: bool = True,
        mass: float | None = None,
        collision_mode: CollisionMode | str = CollisionMode.NORMAL_3D,
        name: str | None = None,
        user_data: dict[str, Any] | None = None,
        *,
        register: bool = True,
    ) -> None:
        self._body_id = int(body_id)
        self.object_id = -1
        self.name = name
        self.pickable = bool(pickable)
        self.user_data: dict[str, Any] = {} if user_data is None else user_data
        self.sim_core: MultiRobotSimulationCore | None = None
        self._collision_mode = coerce_enum(CollisionMode, collision_mode, "collision_mode")
        self._events: EventBus | None = None
        self._callbacks: PeriodicSchedule | None = None  # made on first registration
        self._row = -1  # no row until bound to a simulation or given a standalone store
        if sim_core is not None:
            self.mass = float(mass) if mass is not None else sim_core.body_mass(self.body_id)
            if register:  # subclasses that finish their own setup first pass False and add later
                sim_core.add_object(self)
        else:
            self.mass = float(mass) if mass is not None else self._standalone_mass()
            self._store = KinematicState(1)
            self._row = self._store.allocate(
                -1,
                self.body_id,
                *self._standalone_pose(),
                collision_code=COLLISION_CODES[self._collision_mode.value],
            )

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(object_id={self.object_id}, name={self.name!r}, "
            f"body_id={self._body_id})"
        )

    # ----- the PyBullet body --------------------------------------------------------------

    @property
    def body_id(self) -> int:
        """PyBullet body unique id (-1 for none), ready for raw ``pybullet`` calls: a body
        still pending is created first, and PyBullet's client-side body list is brought up to
        date if bodies were created in batches since (so ``getBodyInfo`` works)."""
        sim = self.sim_core
        if sim is not None:
            world = sim.world
            if self._body_id == PENDING_BODY:
                world.create_pending_bodies()
            world.sync_body_list()
        return self._body_id

    @body_id.setter
    def body_id(self, value: int) -> None:
        self._body_id = int(value)

    @property
    def raw_body_id(self) -> int:
        """The body id without creating a pending body: ``PENDING_BODY`` (-2) while the body
        waits to be created with others (see ``world/pending.py``)."""
        return self._body_id

    def bind_body(self, body_id: int) -> None:
        """Take the PyBullet body created for this object. Called by the world; not for users."""
        self._body_id = int(body_id)

    # ----- binding to a simulation (called by MultiRobotSimulationCore) -------------------

    def bind(
        self, sim: MultiRobotSimulationCore, store: KinematicState, row: int, object_id: int
    ) -> None:
        """Adopt a row in ``sim``'s store. Called by ``sim.add_object``; not for users."""
        self.sim_core = sim
        self._store = store
        self._row = row
        self.object_id = object_id
        if self._logger is not None:
            self._refresh_log_prefix()

    def on_removed(self) -> None:
        """Called by the simulation just before the object leaves it (subclass hook)."""

    def unbind(self) -> None:
        """Leave the simulation, keeping the last pose in a private row."""
        pos, orn = self._store.position[self._row].copy(), self._store.orientation[self._row].copy()
        self._store = KinematicState(1)
        self._row = self._store.allocate(
            -1, self.body_id, pos, orn, collision_code=COLLISION_CODES[self._collision_mode.value]
        )
        self.sim_core = None
        self.object_id = -1
        if self._body_id == PENDING_BODY:
            self._body_id = -1  # left before its body was made: it never will be
        if self._logger is not None:
            self._refresh_log_prefix()

    @property
    def state_row(self) -> int:
        """Row of this object in the state store (stable for its lifetime in a simulation)."""
        return self._row

    # ----- identity, flags, events --------------------------------------------------------

    def set_name(self, name: str | None) -> None:
        """Rename the object and refresh its log prefix."""
        self.name = name
        if self._logger is not None:
            self._refresh_log_prefix()

    @property
    def _log(self) -> NamedLazyLogger:
        """This object's logger (made on first use: most objects never log)."""
        if self._logger is None:
            self._logger = NamedLazyLogger(__name__)
            self._refresh_log_prefix()
        return self._logger

    @property
    def events(self) -> EventBus:
        """Per-entity event bus, created on first access."""
        if self._events is None:
            self._events = EventBus()
            if self.sim_core is not None:
                self.sim_core.world.on_event_bus_created()
        return self._events

    def has_event_bus(self) -> bool:
        """Whether anyone has asked for this object's bus yet (emitters skip it otherwise)."""
        return self._events is not None

    @property
    def collision_mode(self) -> CollisionMode:
        """How the object takes part in collision detection."""
        return self._collision_mode

    @property
    def is_static(self) -> bool:
        """Whether the object is STATIC (never moves)."""
        return self._collision_mode is CollisionMode.STATIC

    def set_collision_mode(self, mode: CollisionMode | str) -> None:
        """Change the collision mode; DISABLED also turns off PyBullet contacts."""
        mode = coerce_enum(CollisionMode, mode, "collision_mode")
        if mode is self._collision_mode:
            return
        old, self._collision_mode = self._collision_mode, mode
        self._store.set_collision_code(self._row, COLLISION_CODES[mode.value])
        if self.sim_core is not None:
            self.sim_core.world.on_collision_mode_changed(self, old, mode)

    # ----- pose ---------------------------------------------------------------------------

    def get_pose(self) -> Pose:
        """Current pose in the world frame (a copy; read from the state store)."""
        return Pose.from_arrays_unchecked(
            self._store.position[self._row].copy(), self._store.orientation[self._row].copy()
        )

    def set_pose(self, pose: Pose, preserve_velocity: bool = True) -> bool:
        """Move the object (and everything attached to it) to ``pose``.

        Returns:
            True if the pose changed, False if it already was ``pose``.
        """
        if not isinstance(pose, Pose):
            raise TypeError(f"set_pose: expected a Pose, got {pose!r}")
        return self._write_pose(pose.position, pose.orientation, preserve_velocity)

    def set_pose_raw(
        self,
        position: Sequence[float] | np.ndarray,
        orientation: Sequence[float] | np.ndarray,
        preserve_velocity: bool = True,
    ) -> bool:
        """Like :meth:`set_pose` from raw ``[x, y, z]`` and ``[x, y, z, w]`` (validated).

        Raises:
            ValueError: for a wrong-length or non-finite position, or a zero quaternion.
        """
        return self._write_pose(
            as_position(position), as_orientation(orientation), preserve_velocity
        )

    def _write_pose(self, pos: np.ndarray, orn: np.ndarray, preserve_velocity: bool) -> bool:
        store, row = self._store, self._row
        if np.array_equal(store.position[row], pos) and np.array_equal(store.orientation[row], orn):
            return False
        store.position[row] = pos
        store.orientation[row] = orn
        store.mark_moved(row)
        if self.sim_core is not None:
            self.sim_core.world.on_pose_written(self, preserve_velocity)
        elif self.body_id >= 0:
            p.resetBasePositionAndOrientation(self.body_id, pos.tolist(), orn.tolist())
            store.dirty[row] = False
        return True

    # ----- attachments --------------------------------------------------------------------

    def attach_object(
        self,
        obj: SimObject,
        parent_link_index: int | str = -1,
        relative_pose: Pose | None = None,
        joint_type: int = p.JOINT_FIXED,
        keep_world_pose: bool = False,
    ) -> bool:
        """Attach ``obj`` to one of this object's links; it follows that link every step.

        Args:
            obj: The object to carry.
            parent_link_index: Link index, link name, -1 or "base_link".
            relative_pose: Child pose in the link frame (default identity).
            joint_type: Only ``pybullet.JOINT_FIXED`` is supported.
            keep_world_pose: Compute ``relative_pose`` so the child stays where it is.

        Returns:
            True once attached.

        Raises:
            ValueError: attaching to itself, an object already attached (to this or another
                parent), a cycle, objects of different simulations, an unknown link, both
                ``relative_pose`` and ``keep_world_pose``, or an unsupported ``joint_type``.
        """
        return self._require_sim("attach_object").world.attach(
            self, obj, parent_link_index, relative_pose, joint_type, keep_world_pose
        )

    def detach_object(
        self, obj: SimObject, drop_pose: Pose | None = None, drop_relative_pose: Pose | None = None
    ) -> bool:
        """Detach ``obj``; optionally put it at ``drop_pose`` or offset by ``drop_relative_pose``.

        Returns:
            True if ``obj`` was attached to this object, False (with a warning) otherwise.

        Raises:
            ValueError: if both ``drop_pose`` and ``drop_relative_pose`` are given.
        """
        return self._require_sim("detach_object").world.detach(
            self, obj, drop_pose, drop_relative_pose
        )

    def get_attached_objects(self) -> list[SimObject]:
        """Objects attached to this one, in attachment order."""
        return [] if self.sim_core is None else self.sim_core.attachments.children_of(self)

    @property
    def attached_objects(self) -> list[SimObject]:
        """Objects attached to this one (same as :meth:`get_attached_objects`)."""
        return self.get_attached_objects()

    def is_attached(self) -> bool:
        """Whether this object is carried by another."""
        return self.sim_core is not None and self.sim_core.attachments.of_child(self) is not None

    def get_attached_parent(self) -> SimObject | None:
        """The object carrying this one, or None."""
        att = None if self.sim_core is None else self.sim_core.attachments.of_child(self)
        return None if att is None else att.parent

    def find_nearest_pickable(self, search_radius: float = 1.0) -> SimObject | None:
        """Nearest pickable, unattached object within ``search_radius`` metres of this one."""
        if self.sim_core is None:
            return None
        return find_nearest(
            self.sim_core.sim_objects,
            self.get_pose().position,
            search_radius,
            predicate=lambda o: o.pickable and not o.is_attached(),
            exclude=self,
        )

    # ----- per-object behaviour -----------------------------------------------------------

    def update(self, dt: float) -> None:
        """Per-step behaviour; subclasses override it and the simulation calls it each step."""

    def overrides_update(self) -> bool:
        """Whether this object's class overrides :meth:`update` (the simulation then calls it
        every step; objects that do not cost nothing)."""
        return type(self).update is not SimObject.update

    def register_callback(
        self, callback: Callable[[SimObject, float], Any], frequency: float = 0.25
    ) -> None:
        """Call ``callback(obj, dt)`` every ``1 / frequency`` seconds of sim time.

        Raises:
            ValueError: if ``frequency`` is not a number > 0.
        """
        if self._callbacks is None:
            self._callbacks = PeriodicSchedule()
        self._callbacks.add(callback, frequency, owner=f"{self!r}.register_callback")
        if self.sim_core is not None:
            self.sim_core.world.on_object_callbacks_changed(self)

    def unregister_callback(self, callback: Callable[..., Any]) -> bool:
        """Remove a callback; return whether it was registered."""
        return self._callbacks is not None and self._callbacks.remove(callback)

    def has_callbacks(self) -> bool:
        """Whether any per-object callbacks are registered."""
        return self._callbacks is not None and len(self._callbacks) > 0

    def execute_callbacks(self, current_time: float) -> None:
        """Run the callbacks due at ``current_time`` (sim seconds)."""
        if self._callbacks is not None:
            for callback, dt in self._callbacks.due(current_time):
                callback(self, dt)

    def callback_steps_until_due(self, step: int, timestep: float, limit: int) -> int:
        """How many steps from ``step`` on (at most ``limit``) run before a callback is due."""
        if self._callbacks is None:
            return limit
        return self._callbacks.steps_until_due(step, timestep, limit)

    def reset_callbacks(self) -> None:
        """Restart the callback schedule from sim time 0."""
        if self._callbacks is not None:
            self._callbacks.reset()

    # ----- helpers ------------------------------------------------------------------------

    def _require_sim(self, what: str) -> MultiRobotSimulationCore:
        if self.sim_core is None:
            raise ValueError(f"{what}: {self!r} is not part of a simulation")
        return self.sim_core

    # A standalone object talks to PyBullet client 0; ``add_object`` re-reads the body from
    # the simulation's own client, so a failed read here only affects standalone use.

    def _standalone_mass(self) -> float:
        try:
            return float(p.getDynamicsInfo(self.body_id, -1)[0]) if self.body_id >= 0 else 0.0
        except p.error:
            return 0.0

    def _standalone_pose(self) -> tuple[Sequence[float], Sequence[float]]:
        try:
            if self.body_id >= 0:
                return p.getBasePositionAndOrientation(self.body_id)
        except p.error:
            pass
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)

    def _refresh_log_prefix(self) -> None:
        label = f"{self.object_id}:{self.name}" if self.name else str(self.object_id)
        assert self._logger is not None
        self._logger.set_prefix(f"[{type(self).__name__}:{label}] ")
