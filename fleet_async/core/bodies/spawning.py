"""Creating the PyBullet bodies of spawn parameters: one at a time, or many at once.

``create_body`` makes one multibody from a SimObjectSpawnParams. ``reserve_body`` is what
``from_params`` uses: on a headless simulation a kinematic body is not made at once but left
pending, and the world creates every pending body of the same shapes in one batch call later
(``world/pending.py``); ``construct`` builds the handle around either. ``create_bodies`` makes many:
PyBullet creates a whole group of identical bodies in one ``createMultiBody(batchPositions=)``
call, about ten times faster per body than one call each at fleet sizes, so spawn parameters
are grouped by their shapes and mass and each group is created in one call; ``wrap_all`` then
wraps every body in its SimObject / Agent. Non-identity orientations are applied afterwards; URDF
agents are loaded one by one (PyBullet has no batch form for them).
"""

from __future__ import annotations

import dataclasses
from collections import defaultdict
from collections.abc import Callable, Sequence
from pathlib import Path as FsPath
from typing import TYPE_CHECKING, TypeVar

import pybullet as p

from fleet_async.core.base.paths import resolve_data_file
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.world.link_colours import one_colour_per_link
from fleet_async.core.world.pending import PENDING_BODY, Deferred, PendingBody
from fleet_async.core.world.shapes import get_or_create_shapes, record_body_shape

if TYPE_CHECKING:
    from fleet_async.core.base.types import CollisionMode
    from fleet_async.core.bodies.host import BodyHost
    from fleet_async.core.bodies.sim_object import SimObject

__all__ = [
    "Deferred",
    "construct",
    "create_bodies",
    "create_body",
    "load_sdf_objects",
    "reserve_bodies",
    "reserve_body",
    "wrap_all",
]


T = TypeVar("T", bound="SimObject")

# PyBullet's batch creation is limited by its command buffer; chunks keep every call safe.
_CHUNK = 4096
_IDENTITY = [0.0, 0.0, 0.0, 1.0]


def _shape_ids(params: SimObjectSpawnParams, sim: BodyHost) -> tuple[int, int]:
    visual, collision = params.visual_shape, params.collision_shape
    if visual is not None and params.visual_frame_pose is not None:
        visual = dataclasses.replace(visual, frame_pose=params.visual_frame_pose)
    if collision is not None and params.collision_frame_pose is not None:
        collision = dataclasses.replace(collision, frame_pose=params.collision_frame_pose)
    paths = sim.params.model_paths
    return get_or_create_shapes(visual, collision, sim.world.client, list(paths) if paths else [])


def reserve_body(
    params: SimObjectSpawnParams, sim_core: BodyHost | None
) -> tuple[int, Deferred | None]:
    """A body for ``params``: ``(body_id, None)`` when made now, ``(PENDING_BODY, deferred)``
    when the world will make it with others.

    Bodies are left pending on a headless simulation when they are kinematic (physics off or
    mass 0); with a GUI, with dynamics or without a simulation they are made at once.

    Raises:
        FileNotFoundError / ValueError: for bad shapes, at once either way.
    """
    if sim_core is None or sim_core.is_gui or (sim_core.params.physics and params.mass > 0):
        return create_body(params, sim_core), None
    visual_id, collision_id = _shape_ids(params, sim_core)
    pose = params.initial_pose
    return PENDING_BODY, (
        PendingBody(visual_id, collision_id, params.mass),
        pose.position,
        pose.orientation,
    )


def construct(
    make: Callable[[int], T],
    body: int,
    deferred: Deferred | None,
    sim_core: BodyHost | None,
) -> T:
    """``make(body)`` for a body from :func:`reserve_body`; a body made for it is removed if
    that fails."""
    if deferred is not None and sim_core is not None:
        world = sim_core.world
        world.expect_pending(deferred)
        try:
            return make(body)
        finally:
            world.expect_pending(None)
    try:
        return make(body)
    except Exception:
        if body >= 0:
            p.removeBody(body, physicsClientId=0 if sim_core is None else sim_core.client)
        raise


def reserve_bodies(
    params_list: Sequence[SimObjectSpawnParams], sim: BodyHost
) -> list[tuple[int, Deferred | None]]:
    """:func:`reserve_body` for many: bodies that can wait are left pending, the others are
    created now in batches (:func:`create_bodies`). Input order kept.

    Raises:
        FileNotFoundError / ValueError: for bad shapes, before any body is created.
    """
    out: list[tuple[int, Deferred | None]] = [(-1, None)] * len(params_list)
    now = []
    for i, params in enumerate(params_list):
        if sim.is_gui or (sim.params.physics and params.mass > 0):
            now.append(i)
        else:
            out[i] = reserve_body(params, sim)
    for i, body in zip(now, create_bodies([params_list[i] for i in now], sim), strict=True):
        out[i] = (body, None)
    return out


def create_bodies(params_list: Sequence[SimObjectSpawnParams], sim: BodyHost) -> list[int]:
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
    sim: BodyHost,
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


def create_body(params: SimObjectSpawnParams, sim_core: BodyHost | None) -> int:
    """Create the PyBullet multibody for ``params`` and return its body id."""
    client = 0 if sim_core is None else sim_core.client
    if sim_core is None and not p.isConnected(physicsClientId=0):
        raise RuntimeError(
            "cannot create a body: no sim_core was given and no PyBullet client is connected; "
            "pass sim_core=MultiRobotSimulationCore(...)"
        )
    search = [] if sim_core is None else list(sim_core.params.model_paths or [])
    visual, collision = params.visual_shape, params.collision_shape
    if visual is not None and params.visual_frame_pose is not None:
        visual = dataclasses.replace(visual, frame_pose=params.visual_frame_pose)
    if collision is not None and params.collision_frame_pose is not None:
        collision = dataclasses.replace(collision, frame_pose=params.collision_frame_pose)
    visual_id, collision_id = get_or_create_shapes(visual, collision, client, search)
    pos, orn = params.initial_pose.as_position_orientation()
    body = p.createMultiBody(
        baseMass=params.mass,
        baseCollisionShapeIndex=collision_id,
        baseVisualShapeIndex=visual_id,
        basePosition=pos,
        baseOrientation=orn,
        physicsClientId=client,
    )
    if body < 0:
        raise ValueError(f"PyBullet could not create a body from {params!r}")
    record_body_shape(client, int(body), collision_id)
    return int(body)


def load_sdf_objects(
    cls: type[T],
    sdf_path: str,
    sim_core: BodyHost | None,
    collision_mode: CollisionMode | str,
    global_scaling: float,
    name_prefix: str | None,
    pickable: bool,
    use_fixed_base: bool,
) -> list[T]:
    """Load every body of an SDF file and wrap each in ``cls`` (``SimObject.from_sdf``).

    If anything fails, nothing this call created is left behind.

    Raises:
        FileNotFoundError: naming the paths tried when the file does not exist.
        ValueError: if PyBullet cannot parse the file.
    """
    search = [] if sim_core is None else list(sim_core.params.model_paths or [])
    path = resolve_data_file(sdf_path, search, "sdf_path")
    client = 0 if sim_core is None else sim_core.client
    try:
        bodies = p.loadSDF(path, globalScaling=float(global_scaling), physicsClientId=client)
    except p.error as exc:
        raise ValueError(f"sdf_path {path!r}: PyBullet could not load it ({exc})") from exc
    prefix = name_prefix if name_prefix is not None else FsPath(path).stem
    objects: list[T] = []
    try:
        for i, body in enumerate(bodies):
            one_colour_per_link(client, body)  # the GUI and recordings show it alike
            if use_fixed_base:
                p.changeDynamics(body, -1, mass=0.0, physicsClientId=client)
            objects.append(
                cls(
                    body,
                    sim_core=sim_core,
                    pickable=pickable,
                    mass=0.0 if use_fixed_base else None,
                    collision_mode=collision_mode,
                    name=f"{prefix}_{i}" if len(bodies) > 1 else prefix,
                )
            )
    except Exception:
        for obj in objects:
            if sim_core is not None:
                sim_core.remove_object(obj)
        for body in bodies[len(objects) :]:
            p.removeBody(body, physicsClientId=client)
        raise
    return objects
