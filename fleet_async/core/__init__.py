"""The synchronous simulator: state store, step loop, events, objects and the PyBullet adapter.

Nothing in ``fleet_async.core`` imports ``fleet_async.tasks``; the async mission layer sits on
top of this package and never inside it.
"""

from fleet_async.core.config_utils import (
    dataclass_from_dict,
    forward_spawn_params,
    load_config,
    load_yaml_config,
    merge_configs,
    resolve_class,
)
from fleet_async.core.events import EventBus, SimEvents
from fleet_async.core.geometry import Path, Pose
from fleet_async.core.logging_utils import (
    LazyLogger,
    NamedLazyLogger,
    get_lazy_logger,
    get_named_lazy_logger,
    wrap_existing_logger,
)
from fleet_async.core.monitor import DataMonitor
from fleet_async.core.params import SimulationParams
from fleet_async.core.plugins import SimPlugin
from fleet_async.core.shapes import ShapeParams
from fleet_async.core.sim_object import SimObject
from fleet_async.core.simulation import MultiRobotSimulationCore
from fleet_async.core.spawn_params import SimObjectSpawnParams
from fleet_async.core.types import (
    ActionStatus,
    CollisionDetectionMethod,
    CollisionMode,
    ControllerMode,
    DoorState,
    DropPhase,
    MotionMode,
    MovementDirection,
    PickPhase,
    PosePhase,
    SpatialHashCellSizeMode,
)

__all__ = [
    "ActionStatus",
    "CollisionDetectionMethod",
    "CollisionMode",
    "ControllerMode",
    "DataMonitor",
    "DoorState",
    "DropPhase",
    "EventBus",
    "LazyLogger",
    "MotionMode",
    "MovementDirection",
    "MultiRobotSimulationCore",
    "NamedLazyLogger",
    "Path",
    "PickPhase",
    "Pose",
    "PosePhase",
    "ShapeParams",
    "SimEvents",
    "SimObject",
    "SimObjectSpawnParams",
    "SimPlugin",
    "SimulationParams",
    "SpatialHashCellSizeMode",
    "dataclass_from_dict",
    "forward_spawn_params",
    "get_lazy_logger",
    "get_named_lazy_logger",
    "load_config",
    "load_yaml_config",
    "merge_configs",
    "resolve_class",
    "wrap_existing_logger",
]
