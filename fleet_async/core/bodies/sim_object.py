"""SimObject: a handle onto one row of the simulation's state store.

A SimObject owns no pose of its own: ``get_pose`` reads the store, ``set_pose`` writes it and
marks the row dirty. An object created without a simulation keeps its own pose and what it
carries (``standalone.py``), talking to PyBullet client 0 directly, until ``sim.add_object``
adopts it.

A STATIC object "never moves" (the reference API's CollisionMode): ``set_pose`` refuses it with
a warning and returns False, until ``set_collision_mode`` makes it movable.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar, cast

import numpy as np
import pybullet as p

from fleet_async.core.base.events import EventBus
from fleet_async.core.base.logging_utils import NamedLazyLogger
from fleet_async.core.base.scheduling import PeriodicSchedule
from fleet_async.core.base.types import CollisionMode, coerce_enum
from fleet_async.core.bodies.constructors import SimObjectConstructors
from fleet_async.core.bodies.object_callbacks import ObjectCallbacks
from fleet_async.core.bodies.removal import ObjectRemovedError, RemovedState, removed_message
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.bodies.standalone import StandaloneState, read_standalone_mass
from fleet_async.core.geometry.approach import find_nearest
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.vectors import as_orientation, as_position
from fleet_async.core.world.pending import PENDING_BODY
from fleet_async.core.world.shapes import ShapeParams
from fleet_async.core.world.state import COLLISION_CODES, KinematicState

if TYPE_CHECKING:
    from fleet_async.core.bodies.host import BodyHost

__all__ = ["ObjectRemovedError", "ShapeParams", "SimObject", "SimObjectSpawnParams"]

logger = logging.getLogger(__name__)


class SimObject(ObjectCallbacks, SimObjectConstructors):
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
        object_id: Unique id assigned by the simulation (-1 while standalone); ``name``,
            ``body_id``, ``mass``, ``pickable``, ``user_data`` and ``sim_core`` as given.
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
        sim_core: BodyHost | None = None,
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
        self.sim_core: BodyHost | None = None
        self._collision_mode = coerce_enum(CollisionMode, collision_mode, "collision_mode")
        self._events: EventBus | None = None
        self._callbacks = PeriodicSchedule()
        self._row = -1  # no row until bound to a simulation or given a standalone store
        self._removed: str | None = None  # why using the object fails once it left its sim
        self._solo: StandaloneState | None = None
        if sim_core is not None:
            # mass=None: the body's own masses, every link summed (what a URDF says).
            self.mass = float(mass) if mass is not None else sim_core.body_total_mass(body_id)
            if register:  # subclasses that finish their own setup first pass False and add later
                sim_core.add_object(self)
        else:
            self.mass = float(mass) if mass is not None else read_standalone_mass(self.body_id)
            self._go_standalone(None)

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(object_id={self.object_id}, name={self.name!r}, "
            f"body_id={self._body_id})"
        )

    # ----- the PyBullet body --------------------------------------------------------------

    @property
    def body_id(self) -> int:
        """PyBullet body unique id (-1 for none), ready for raw ``pybullet`` calls: a body
        still pending is created first (with every pending body made from shapes; a URDF
        robot's alone), and PyBullet's client-side body list is brought up to
        date if bodies were created in batches since (so ``getBodyInfo`` works)."""
        sim = self.sim_core
        if sim is not None:
            world = sim.world
            if self._body_id == PENDING_BODY:
                world.create_pending_bodies_for([self._row], for_raw_access=True)
            world.sync_body_list()
        return self._body_id

    @body_id.setter
    def body_id(self, value: int) -> None:
        self._body_id = int(value)

    @property
    def server_body_id(self) -> int:
        """The body id for calls PyBullet's server answers (poses, masses, dynamics, contact
        filters, link states): a pending body is created first, but PyBullet's client-side
        body list is not brought up to date (``getBodyInfo`` may not know the body yet).
        What the simulation itself uses, so that its own reads never cost a body-list sync."""
        if self._body_id == PENDING_BODY and self.sim_core is not None:
            self.sim_core.world.create_pending_bodies_for([self._row])
        return self._body_id

    @property
    def raw_body_id(self) -> int:
        """The body id without creating a pending body: ``PENDING_BODY`` (-2) while the body
        waits to be created with others (see ``world/pending.py``)."""
        return self._body_id

    def bind_body(self, body_id: int) -> None:
        """Take the PyBullet body created for this object. Called by the world; not for users."""
        self._body_id = int(body_id)

    # ----- binding to a simulation (called by BodyHost) -------------------

    def bind(self, sim: BodyHost, store: KinematicState, row: int, object_id: int) -> None:
        """Adopt a row in ``sim``'s store. Called by ``sim.add_object``; not for users."""
        self.sim_core = sim
        self._store = store
        self._row = row
        self._solo = None
        self._removed = None
        self.object_id = object_id
        if self._logger is not None:
            self._refresh_log_prefix()

    def on_removed(self) -> None:
        """Called by the simulation just before the object leaves it (subclass hook)."""

    def unbind(self) -> None:
        """Leave the simulation; from now on using the object raises ObjectRemovedError."""
        if self._body_id == PENDING_BODY:
            self._body_id = -1  # left before its body was made: it never will be
        self._removed = removed_message(self, self.sim_core)
        self._store = cast("KinematicState", RemovedState(self._removed))
        self._row = self.object_id = -1
        self.sim_core = None

    @property
    def is_removed(self) -> bool:
        """Whether the object has left the simulation it belonged to."""
        return self._removed is not None

    def check_not_removed(self, what: str) -> None:
        """Raise ObjectRemovedError (naming the object and ``what``) if it left its sim."""
        if self._removed is not None:
            raise ObjectRemovedError(f"{what}: {self._removed}")

    def _go_standalone(self, pose: tuple[Sequence[float], Sequence[float]] | None) -> None:
        self._solo = StandaloneState(self, COLLISION_CODES[self._collision_mode.value], pose)
        self._store, self._row = self._solo.store, self._solo.row

    @property
    def standalone_state(self) -> StandaloneState | None:
        """Pose and attachments kept while outside a simulation (None inside one)."""
        return self._solo

    @property
    def state_row(self) -> int:
        """Row of this object in the state store (stable for its lifetime in a simulation)."""
        return self._row

    # ----- identity, flags, events --------------------------------------------------------

    def set_name(self, name: str | None) -> None:
        """Rename the object and refresh its log prefix."""
        self.name = name
        self._refresh_log_prefix()

    @property
    def events(self) -> EventBus:
        """Per-entity event bus, created on first access."""
        if self._events is None:
            self._events = EventBus(on_change=self._on_handlers_changed)
            if self.sim_core is not None:
                self.sim_core.world.on_event_bus_created()
        return self._events

    def _on_handlers_changed(self, event: str) -> None:
        if self.sim_core is not None:
            self.sim_core.world.on_entity_handlers_changed(self)

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

    @property
    def is_kinematic(self) -> bool:
        """Whether the object is massless (``mass == 0``), as the reference implementation says.

        A massless body is only ever moved by the simulator. With physics off every body is
        moved that way, whatever its mass.
        """
        return self.mass == 0.0

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
            True if the pose changed; False if it already was ``pose``, or (with a warning) if
            the object is STATIC: change its collision mode first to move it.
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
        if self._collision_mode is CollisionMode.STATIC:
            self._log.warning(
                "set_pose refused: a STATIC object never moves; "
                "call set_collision_mode(...) first to move it"
            )
            return False
        if self._solo is not None:
            self._solo.write_pose(pos, orn)
            return True
        store.position[row] = pos
        store.orientation[row] = orn
        store.mark_moved(row)
        if self.sim_core is not None:
            self.sim_core.world.on_pose_written(self, preserve_velocity)
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

        Works inside a simulation and outside one (both objects without a simulation; see
        ``standalone.py``).

        Returns:
            True once attached; False, with a warning, for an object that is not pickable, one
            already attached (to this or another parent: the reference API's contract, "False
            otherwise") or a link name this object does not have (naming the body's links).

        Raises:
            ValueError: attaching to itself, a cycle, objects of different simulations, a link
                index out of range, both ``relative_pose`` and ``keep_world_pose``, or an
                unsupported ``joint_type``.
        """
        if joint_type != p.JOINT_FIXED:
            raise ValueError(
                f"attach_object: joint_type {joint_type!r} is not supported; "
                "only pybullet.JOINT_FIXED (4) is"
            )
        if not obj.pickable and obj is not self:
            logger.warning("attach_object: %r is not pickable (pickable=False); not attached", obj)
            return False
        if self._solo is not None:
            if obj.sim_core is not None:
                raise ValueError(
                    f"attach_object: {obj!r} is part of a simulation and {self!r} is not"
                )
            return self._solo.attach(obj, parent_link_index, relative_pose, keep_world_pose)
        return self._require_sim("attach_object").world.attach(
            self, obj, parent_link_index, relative_pose, keep_world_pose
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
        if self._solo is not None:
            return self._solo.detach(obj, drop_pose, drop_relative_pose)
        return self._require_sim("detach_object").world.detach(
            self, obj, drop_pose, drop_relative_pose
        )

    def get_attached_objects(self) -> list[SimObject]:
        """Objects attached to this one, in attachment order."""
        if self._solo is not None:
            return self._solo.children()
        return self._require_sim("get_attached_objects").attachments.children_of(self)

    @property
    def attached_objects(self) -> list[SimObject]:
        """Objects attached to this one (same as :meth:`get_attached_objects`)."""
        return self.get_attached_objects()

    def is_attached(self) -> bool:
        """Whether this object is carried by another."""
        return self.get_attached_parent() is not None

    def get_attached_parent(self) -> SimObject | None:
        """The object carrying this one, or None."""
        if self._solo is not None:
            return self._solo.parent()
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

    def _require_sim(self, what: str) -> BodyHost:
        self.check_not_removed(what)
        if self.sim_core is None:
            raise ValueError(f"{what}: {self!r} is not part of a simulation")
        return self.sim_core

    @property
    def _log(self) -> NamedLazyLogger:
        """This object's logger (made on first use: most objects never log)."""
        if self._logger is None:
            self._logger = NamedLazyLogger(__name__)
            self._refresh_log_prefix()
        return self._logger

    def _refresh_log_prefix(self) -> None:
        if self._logger is None:
            return
        label = f"{self.object_id}:{self.name}" if self.name else str(self.object_id)
        self._logger.set_prefix(f"[{type(self).__name__}:{label}] ")
