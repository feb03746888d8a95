"""Enumerations shared across the simulator.

The reference API's ``types`` module: a thin facade over the modules of the core that own these
names, so a pybullet_fleet script ports by renaming its import (``pybullet_fleet.types`` becomes
``fleet_async.types``). Nothing in fleet_async imports this module.
"""

from __future__ import annotations

from fleet_async.core.base.types import (
    ActionStatus,
    CollisionDetectionMethod,
    CollisionMode,
    ControllerMode,
    DoorState,
    MotionMode,
    MovementDirection,
    PosePhase,
    SpatialHashCellSizeMode,
)

__all__ = [
    "ActionStatus",
    "CollisionDetectionMethod",
    "CollisionMode",
    "ControllerMode",
    "DoorState",
    "MotionMode",
    "MovementDirection",
    "PosePhase",
    "SpatialHashCellSizeMode",
]
