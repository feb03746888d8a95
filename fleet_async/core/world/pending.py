"""Bodies spawned one at a time but created in PyBullet together.

A loop of ``Agent.from_mesh`` / ``SimObject.from_params`` on a headless simulation does not call
``createMultiBody`` once per object: each object gets its row (its pose, its handle, its
collision mode) at once and its body is *pending*. A kinematic simulation needs no PyBullet
body to move its objects or to check their collisions (poses live in the state store; box pairs
are measured with numpy and other shapes are queried as (shape, pose)), so pending bodies are
created only when something needs PyBullet's view: reading an object's ``body_id``,
``sim.client`` (raw PyBullet calls), ``sim.sync_pybullet()``, a recording, a physics step, a
contact-point or compound-body query. Then all of them are created at once, in one
``createMultiBody(batchPositions=...)`` call per group of identical shapes and mass (about ten
times cheaper per body than one call each). The first body of each shape is created as soon as
the collision system registers it, to measure the shape.

Robots of a URDF model the simulation already loaded once are pending too
(``world/urdf_models.py``): their group is the model, and each is loaded with ``loadURDF`` when
the bodies are created (a URDF body cannot be made in a batch call), at its row's pose. Until
then the collision system bounds them by the model's box and the trace by its first body.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pybullet as p

from fleet_async.core.world.shapes import record_body_shape
from fleet_async.core.world.state import COLLISION_CODES, KinematicState
from fleet_async.core.world.urdf_models import UrdfKey, UrdfModel, load_urdf_body

if TYPE_CHECKING:
    from fleet_async.core.world.backend import PyBulletBackend
    from fleet_async.core.world.host import PendingHandle

__all__ = [
    "PENDING_BODY",
    "Deferred",
    "PendingBodies",
    "PendingBodiesApi",
    "PendingBody",
    "UrdfSpawn",
]

PENDING_BODY = -2
"""The body id of an object whose PyBullet body is not created yet."""

# PyBullet's batch creation is limited by its command buffer; chunks keep every call safe.
_CHUNK = 4096
_DISABLED = COLLISION_CODES["disabled"]


@dataclass(frozen=True)
class PendingBody:
    """What it takes to create one body later: its shapes (PyBullet ids, -1 for none) and
    mass (kg); the pose is the row's pose at creation time."""

    visual_shape: int
    collision_shape: int
    mass: float


@dataclass(frozen=True)
class UrdfSpawn:
    """A URDF robot waiting for its body: its model, the URDF link-frame pose it was spawned
    at and the base pose ``loadURDF`` gives that (``UrdfModel.base_pose``, its row's pose)."""

    key: UrdfKey
    position: tuple[float, ...]
    orientation: tuple[float, ...]
    base_position: tuple[float, ...]
    base_orientation: tuple[float, ...]


Group = PendingBody | UrdfKey
"""What pending bodies are grouped by: their shapes and mass, or their URDF model."""


class PendingBodies:
    """Bodies waiting to be created, grouped by (visual shape, collision shape, mass) or by
    URDF model; and the URDF models of the simulation."""

    def __init__(self) -> None:
        self._groups: dict[Group, dict[int, PendingHandle]] = {}  # row -> handle, in order
        self._of_row: dict[int, Group] = {}
        self._spawns: dict[int, UrdfSpawn] = {}  # row -> how its URDF robot was spawned
        self.models: dict[UrdfKey, UrdfModel] = {}
        """The URDF models loaded once in this simulation."""

    def collision_shape(self, row: int) -> int:
        """The collision shape the pending body of ``row`` will have (-1: none pending, or a
        URDF body)."""
        body = self._of_row.get(row)
        return body.collision_shape if isinstance(body, PendingBody) else -1

    def visual_shape(self, row: int) -> int:
        """The visual shape the pending body of ``row`` will have (-1: none, none pending, or a
        URDF body)."""
        body = self._of_row.get(row)
        return body.visual_shape if isinstance(body, PendingBody) else -1

    def group(self, row: int) -> Group | None:
        """What the pending body of ``row`` is made from (None: no pending body)."""
        return self._of_row.get(row)

    def __len__(self) -> int:
        return len(self._of_row)

    def add(self, body: PendingBody | UrdfSpawn, row: int, obj: PendingHandle) -> None:
        """Queue the body of ``obj`` (which holds ``row``)."""
        group: Group = body.key if isinstance(body, UrdfSpawn) else body
        if isinstance(body, UrdfSpawn):
            self._spawns[row] = body
        self._groups.setdefault(group, {})[row] = obj
        self._of_row[row] = group

    def discard(self, row: int) -> None:
        """Forget the pending body of ``row`` (its object left before it was created)."""
        body = self._of_row.pop(row, None)
        if body is not None:
            del self._groups[body][row]
            self._spawns.pop(row, None)

    def clear(self) -> None:
        """Forget every pending body and URDF model (the world is being reset)."""
        self._groups.clear()
        self._of_row.clear()
        self._spawns.clear()
        self.models.clear()

    def create_one(self, row: int, store: KinematicState, client: int) -> None:
        """Create the pending body of ``row`` alone (to measure its shape)."""
        body = self._of_row.pop(row, None)
        if body is None:
            return
        obj = self._groups[body].pop(row)
        _place(body, {row: obj}, store, client, self._spawns)

    def create_all(self, store: KinematicState, client: int, one_by_one: bool = False) -> bool:
        """Create every pending body at its row's current pose, in spawn order per group, and
        hand each object its body id (``one_by_one``: one PyBullet call per body, which
        keeps the client-side body list current).

        Returns:
            Whether PyBullet's client-side body list now lacks some of them (a batch of more
            than one body tells the client only about its last body; ``syncBodyInfo`` fixes
            that, at about 80 us per body in the world, so it is left to whoever needs it).
        """
        groups, self._groups = self._groups, {}
        spawns, self._spawns = self._spawns, {}
        self._of_row.clear()
        partial = False
        for body, members in groups.items():
            partial |= _place(body, members, store, client, spawns, 1 if one_by_one else _CHUNK)
        return partial


def _place(
    body: Group,
    members: dict[int, PendingHandle],
    store: KinematicState,
    client: int,
    spawns: dict[int, UrdfSpawn],
    chunk_size: int = _CHUNK,
) -> bool:
    """Create ``members``' bodies in chunks; return whether a chunk held more than one."""
    if isinstance(body, UrdfKey):
        _load_urdfs(members, store, client, spawns)
        return False
    rows = list(members)
    partial = False
    for start in range(0, len(rows), chunk_size):
        chunk = np.array(rows[start : start + chunk_size], dtype=np.int64)
        ids = _create(body, store, chunk, client)
        partial |= len(ids) > 1
        store.body_id[chunk] = ids
        store.dirty[chunk] = False
        for row, body_id in zip(chunk.tolist(), ids, strict=True):
            members[row].bind_body(body_id)
            record_body_shape(client, body_id, body.collision_shape)
        for row in chunk[store.collision_mode[chunk] == _DISABLED].tolist():
            p.setCollisionFilterGroupMask(int(store.body_id[row]), -1, 0, 0, physicsClientId=client)
    return partial


def _load_urdfs(
    members: dict[int, PendingHandle],
    store: KinematicState,
    client: int,
    spawns: dict[int, UrdfSpawn],
) -> None:
    """Load one body per member, in spawn order, where it was spawned; one whose row moved
    since is then put at its row's pose, as a loaded body that moved would be."""
    for row, obj in members.items():
        spawn = spawns[row]
        body_id = load_urdf_body(spawn.key, spawn.position, spawn.orientation, client)
        pos, orn = store.position[row].tolist(), store.orientation[row].tolist()
        if tuple(pos) != spawn.base_position or tuple(orn) != spawn.base_orientation:
            p.resetBasePositionAndOrientation(body_id, pos, orn, physicsClientId=client)
        store.body_id[row] = body_id
        store.dirty[row] = False
        obj.bind_body(body_id)
        if store.collision_mode[row] == _DISABLED:
            p.setCollisionFilterGroupMask(body_id, -1, 0, 0, physicsClientId=client)


def _create(body: PendingBody, store: KinematicState, rows: np.ndarray, client: int) -> list[int]:
    """Create one body per row in one PyBullet call; set the rotated ones' orientations."""
    positions = store.position[rows].tolist()
    created = p.createMultiBody(
        baseMass=body.mass,
        baseCollisionShapeIndex=body.collision_shape,
        baseVisualShapeIndex=body.visual_shape,
        basePosition=positions[0],
        batchPositions=positions,
        physicsClientId=client,
    )
    ids = [int(b) for b in created] if isinstance(created, (list, tuple)) else [int(created)]
    if len(ids) != len(rows) or min(ids) < 0:
        for b in ids:
            if b >= 0:
                p.removeBody(b, physicsClientId=client)
        raise RuntimeError(f"PyBullet created {len(ids)} bodies for a batch of {len(rows)}")
    orn = store.orientation[rows]
    rotated = np.flatnonzero(orn[:, :3].any(axis=1) | (orn[:, 3] != 1.0))
    for k in rotated.tolist():
        p.resetBasePositionAndOrientation(
            ids[k], positions[k], orn[k].tolist(), physicsClientId=client
        )
    return ids


Deferred = tuple[
    PendingBody | UrdfSpawn, "Sequence[float] | np.ndarray", "Sequence[float] | np.ndarray"
]
"""A pending body and the pose (position, orientation) its object joins at (for a URDF body,
PyBullet's base pose: ``UrdfModel.base_pose``)."""


class PendingBodiesApi:
    """The world's pending bodies: what handles and the collision system ask about them
    (mixed into ``World``)."""

    # Provided by World.
    _pending: PendingBodies
    _store: KinematicState
    _backend: PyBulletBackend
    _body_list_stale: bool
    _expected: Deferred | None

    @property
    def has_pending_bodies(self) -> bool:
        """Whether spawned objects wait for their PyBullet bodies to be created."""
        return len(self._pending) > 0

    def create_pending_bodies(self, for_raw_access: bool = False) -> None:
        """Create the PyBullet bodies of every object spawned with a pending body.

        Args:
            for_raw_access: The caller will read PyBullet's client-side body list (a user's
                ``obj.body_id``). Bodies created in one batch call would then need a
                ``syncBodyInfo``, whose cost grows with every body in the world; when fewer
                bodies are pending than exist already, they are created one call each
                instead, so a spawn loop that reads ``body_id`` stays linear.
        """
        pending = len(self._pending)
        if not pending:
            return
        one_by_one = for_raw_access and pending <= self._store.count - pending
        if self._pending.create_all(self._store, self._backend.client, one_by_one=one_by_one):
            self._body_list_stale = True

    def create_pending_bodies_for(
        self, rows: Sequence[int] | np.ndarray, for_raw_access: bool = False
    ) -> None:
        """Create the bodies ``rows`` wait for: a URDF robot's alone (URDF bodies are loaded
        one at a time anyway, so its fleet keeps waiting), and every pending body if one of
        ``rows`` waits for a body made from shapes (in batches: ``create_pending_bodies``)."""
        pending = self._pending
        shaped = False
        for row in np.asarray(rows, dtype=np.int64).tolist():
            group = pending.group(row)
            if isinstance(group, UrdfKey):
                pending.create_one(row, self._store, self._backend.client)
            elif group is not None:
                shaped = True
        if shaped:
            self.create_pending_bodies(for_raw_access)

    def create_pending_body(self, row: int) -> None:
        """Create the pending body of ``row`` alone (the others stay pending)."""
        self._pending.create_one(row, self._store, self._backend.client)

    def pending_collision_shape(self, row: int) -> int:
        """The collision shape id of the body ``row`` waits for (-1: no pending body)."""
        return self._pending.collision_shape(row)

    def pending_visual_shape(self, row: int) -> int:
        """The visual shape id of the body ``row`` waits for (-1: none, or no pending body)."""
        return self._pending.visual_shape(row)

    def pending_group(self, row: int) -> PendingBody | UrdfKey | None:
        """What the body ``row`` waits for is made from: its shapes and mass, or its URDF
        model (None: no pending body). Rows of one group get identical bodies."""
        return self._pending.group(row)

    def pending_urdf_frame(self, row: int) -> tuple[np.ndarray, np.ndarray] | None:
        """Body-frame AABB (centre offset, half extents; m) of the URDF body ``row`` waits
        for, joints at rest (None: not a pending URDF body)."""
        key = self._pending.group(row)
        if not isinstance(key, UrdfKey):
            return None
        model = self._pending.models[key]
        return model.center, model.half

    def urdf_model(self, key: UrdfKey) -> UrdfModel | None:
        """The model ``key`` if this simulation loaded it once (None: not yet)."""
        return self._pending.models.get(key)

    def remember_urdf_model(self, model: UrdfModel) -> None:
        """Keep ``model``: later robots of it may wait for their bodies."""
        self._pending.models[model.key] = model

    def sync_body_list(self) -> None:
        """Make PyBullet's client-side body list (``getBodyInfo``, ``getNumBodies``) know every
        body created in batches (``pybullet.syncBodyInfo``; about 80 us per body in the
        world, so only raw access through ``obj.body_id`` asks for it)."""
        if self._body_list_stale:
            p.syncBodyInfo(physicsClientId=self._backend.client)
            self._body_list_stale = False

    def expect_pending(self, deferred: Deferred | None) -> None:
        """The next object added with body id ``PENDING_BODY`` joins at this (body, position,
        orientation) and its body is created later, with others; None withdraws it."""
        self._expected = deferred
