"""Bodies spawned one at a time but created in PyBullet together.

A loop of ``Agent.from_mesh`` / ``SimObject.from_params`` on a headless simulation does not call
``createMultiBody`` once per object: each object gets its row (its pose, its handle, its
collision mode) at once and its body is *pending*. Pending bodies are created in one
``createMultiBody(batchPositions=...)`` call per group of identical shapes and mass (about ten
times cheaper per body than one call each, and a single call does not grow with the number of
bodies already in the world), at the start of the next step, or as soon as anything needs
PyBullet's view: reading an object's ``body_id``, ``sim.client`` (raw PyBullet calls),
``sim.sync_pybullet()``, a collision query on a new shape.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pybullet as p

from fleet_async.core.world.shapes import record_body_shape
from fleet_async.core.world.state import COLLISION_CODES, KinematicState

if TYPE_CHECKING:
    from fleet_async.core.bodies.sim_object import SimObject

__all__ = ["PENDING_BODY", "PendingBodies", "PendingBody"]

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


class PendingBodies:
    """Bodies waiting to be created, grouped by (visual shape, collision shape, mass)."""

    def __init__(self) -> None:
        self._groups: dict[PendingBody, dict[int, SimObject]] = {}  # row -> handle, in order
        self._count = 0

    def __len__(self) -> int:
        return self._count

    def add(self, body: PendingBody, row: int, obj: SimObject) -> None:
        """Queue the body of ``obj`` (which holds ``row``)."""
        self._groups.setdefault(body, {})[row] = obj
        self._count += 1

    def discard(self, row: int) -> None:
        """Forget the pending body of ``row`` (its object left before it was created)."""
        for members in self._groups.values():
            if members.pop(row, None) is not None:
                self._count -= 1
                return

    def clear(self) -> None:
        """Forget every pending body (the world is being reset)."""
        self._groups.clear()
        self._count = 0

    def create_all(self, store: KinematicState, client: int) -> bool:
        """Create every pending body at its row's current pose, in spawn order per group, and
        hand each object its body id.

        Returns:
            Whether PyBullet's client-side body list now lacks some of them (a batch of more
            than one body tells the client only about its last body; ``syncBodyInfo`` fixes
            that, at about 80 us per body in the world, so it is left to whoever needs it).
        """
        groups, self._groups, self._count = self._groups, {}, 0
        partial = False
        for body, members in groups.items():
            rows = list(members)
            for start in range(0, len(rows), _CHUNK):
                chunk = np.array(rows[start : start + _CHUNK], dtype=np.int64)
                ids = _create(body, store, chunk, client)
                partial |= len(ids) > 1
                store.body_id[chunk] = ids
                store.dirty[chunk] = False
                for row, body_id in zip(chunk.tolist(), ids, strict=True):
                    members[row].bind_body(body_id)
                    record_body_shape(client, body_id, body.collision_shape)
                for row in chunk[store.collision_mode[chunk] == _DISABLED].tolist():
                    p.setCollisionFilterGroupMask(
                        int(store.body_id[row]), -1, 0, 0, physicsClientId=client
                    )
        return partial


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
