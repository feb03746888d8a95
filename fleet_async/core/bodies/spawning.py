"""Spawning many objects at once.

PyBullet creates a whole group of identical bodies in one ``createMultiBody(batchPositions=)``
call, about ten times faster per body than one call each at fleet sizes. This module groups
spawn parameters by their shapes and mass, creates each group's bodies in one call, then wraps
every body in its SimObject / Agent. Non-identity orientations are applied afterwards; URDF
agents are loaded one by one (PyBullet has no batch form for them).
"""

from __future__ import annotations

import dataclasses
from collections import defaultdict
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, TypeVar

import pybullet as p

from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.world.shapes import get_or_create_shapes, record_body_shape

if TYPE_CHECKING:
    from fleet_async.core.bodies.sim_object import SimObject
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["create_bodies", "wrap_all"]

T = TypeVar("T", bound="SimObject")

# PyBullet's batch creation is limited by its command buffer; chunks keep every call safe.
_CHUNK = 4096
_IDENTITY = [0.0, 0.0, 0.0, 1.0]


def _shape_ids(params: SimObjectSpawnParams, sim: MultiRobotSimulationCore) -> tuple[int, int]:
    visual, collision = params.visual_shape, params.collision_shape
    if visual is not None and params.visual_frame_pose is not None:
        visual = dataclasses.replace(visual, frame_pose=params.visual_frame_pose)
    if collision is not None and params.collision_frame_pose is not None:
        collision = dataclasses.replace(collision, frame_pose=params.collision_frame_pose)
    return get_or_create_shapes(visual, collision, sim.client, list(sim.params.model_paths or []))


def create_bodies(
    params_list: Sequence[SimObjectSpawnParams], sim: MultiRobotSimulationCore
) -> list[int]:
    """Create one PyBullet body per entry (shape-based params only); return ids in input order.

    Raises:
        FileNotFoundError / ValueError: for bad shapes, before any body is created.
    """
    groups: dict[tuple[int, int, float], list[int]] = defaultdict(list)
    for i, params in enumerate(params_list):
        visual_id, collision_id = _shape_ids(params, sim)
        groups[(visual_id, collision_id, params.mass)].append(i)
    bodies = [-1] * len(params_list)
    client = sim.client
    try:
        for (visual_id, collision_id, mass), members in groups.items():
            for start in range(0, len(members), _CHUNK):
                chunk = members[start : start + _CHUNK]
                positions = [params_list[i].initial_pose.position.tolist() for i in chunk]
                created = p.createMultiBody(
                    baseMass=mass,
                    baseCollisionShapeIndex=collision_id,
                    baseVisualShapeIndex=visual_id,
                    basePosition=positions[0],
                    batchPositions=positions,
                    physicsClientId=client,
                )
                ids = list(created) if isinstance(created, (list, tuple)) else [created]
                if len(ids) != len(chunk) or min(ids) < 0:
                    raise ValueError(
                        f"PyBullet created {len(ids)} bodies for a batch of {len(chunk)}"
                    )
                for i, body, pos in zip(chunk, ids, positions, strict=True):
                    bodies[i] = int(body)
                    record_body_shape(client, int(body), collision_id)
                    orn = params_list[i].initial_pose.orientation.tolist()
                    if orn != _IDENTITY:
                        p.resetBasePositionAndOrientation(body, pos, orn, physicsClientId=client)
    except Exception:
        for body in bodies:
            if body >= 0:
                p.removeBody(body, physicsClientId=client)
        raise
    return bodies


def wrap_all(
    bodies: Sequence[int],
    make: Callable[[int, int], T],
    sim: MultiRobotSimulationCore,
) -> list[T]:
    """Wrap each body with ``make(index, body)``; on failure remove what was built, re-raise."""
    made: list[T] = []
    try:
        for i, body in enumerate(bodies):
            made.append(make(i, body))
    except Exception:
        for obj in made:
            sim.remove_object(obj)
        for body in bodies[len(made) :]:
            if body >= 0:
                p.removeBody(body, physicsClientId=sim.client)
        raise
    return made
