"""Simulation objects, their spawn parameters and shapes.

The reference API's ``sim_object`` module: a thin facade over the modules of the core that own
these names, so a pybullet_fleet script ports by renaming its import
(``pybullet_fleet.sim_object`` becomes ``fleet_async.sim_object``). Nothing in fleet_async
imports this module.
"""

from __future__ import annotations

from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.world.shapes import ShapeParams

__all__ = ["ShapeParams", "SimObject", "SimObjectSpawnParams"]
