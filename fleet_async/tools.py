"""Velocity frames, vector parameters, link lookup, offset poses, grids, nearest search.

The reference API's ``tools`` module: a thin facade over the modules of the core that own these
names, so a pybullet_fleet script ports by renaming its import (``pybullet_fleet.tools`` becomes
``fleet_async.tools``). Nothing in fleet_async imports this module.
"""

from __future__ import annotations

from fleet_async.core.geometry.approach import calculate_offset_pose, find_nearest
from fleet_async.core.geometry.grids import (
    grid_execution,
    grid_to_world,
    grid_to_world_2d,
    world_to_grid,
    world_to_grid_2d,
)
from fleet_async.core.geometry.vectors import (
    body_to_world_velocity_2d,
    body_to_world_velocity_3d,
    normalize_vector_param,
)
from fleet_async.core.world.links import resolve_joint_index, resolve_link_index

__all__ = [
    "body_to_world_velocity_2d",
    "body_to_world_velocity_3d",
    "calculate_offset_pose",
    "find_nearest",
    "grid_execution",
    "grid_to_world",
    "grid_to_world_2d",
    "normalize_vector_param",
    "resolve_joint_index",
    "resolve_link_index",
    "world_to_grid",
    "world_to_grid_2d",
]
