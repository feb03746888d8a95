"""The synchronous simulator: state store, step loop, events, objects and the PyBullet adapter.

Nothing in ``fleet_async.core`` imports ``fleet_async.tasks``; the async mission layer sits on
top of this package and never inside it.
"""

from fleet_async.core.action import (
    DEFAULT_EE_TOLERANCE,
    DEFAULT_JOINT_TOLERANCE,
    DEFAULT_MAX_FORCE,
    DEFAULT_MOVE_SKIP_THRESHOLD,
    Action,
    MoveAction,
    WaitAction,
)
from fleet_async.core.agent import Agent
from fleet_async.core.agent_manager import AgentManager
from fleet_async.core.agent_params import AgentSpawnParams, IKParams
from fleet_async.core.agent_plugins import AgentPlugin, BatteryPlugin
from fleet_async.core.arm_actions import JointAction, PoseAction
from fleet_async.core.checkpoint import CheckpointError
from fleet_async.core.config_utils import (
    dataclass_from_dict,
    forward_spawn_params,
    load_config,
    load_yaml_config,
    merge_configs,
    resolve_class,
)
from fleet_async.core.controllers import (
    Controller,
    ControllerParams,
    DifferentialController,
    KinematicController,
    OmniController,
    PatrolController,
    RandomWalkController,
    create_controller,
    register_controller,
)
from fleet_async.core.events import EventBus, SimEvents
from fleet_async.core.geometry import Path, Pose
from fleet_async.core.grid_spawn import GridSpawnParams
from fleet_async.core.kpis import FleetKpis, KpiCollector, RobotKpis
from fleet_async.core.logging_utils import (
    LazyLogger,
    NamedLazyLogger,
    get_lazy_logger,
    get_named_lazy_logger,
    wrap_existing_logger,
)
from fleet_async.core.managers import SimObjectManager, register_entity_class
from fleet_async.core.models import (
    add_model_search_path,
    list_model_search_paths,
    list_models,
    register_model,
    remove_model_search_path,
    resolve_model,
)
from fleet_async.core.monitor import DataMonitor
from fleet_async.core.params import SimulationParams
from fleet_async.core.pick_drop import DropAction, PickAction
from fleet_async.core.plugins import SimPlugin
from fleet_async.core.recording import SimulationRecorder
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
from fleet_async.core.world_loader import WorldLoadError, WorldLoadFailure

__all__ = [
    "DEFAULT_EE_TOLERANCE",
    "DEFAULT_JOINT_TOLERANCE",
    "DEFAULT_MAX_FORCE",
    "DEFAULT_MOVE_SKIP_THRESHOLD",
    "Action",
    "ActionStatus",
    "Agent",
    "AgentManager",
    "AgentPlugin",
    "AgentSpawnParams",
    "BatteryPlugin",
    "CheckpointError",
    "CollisionDetectionMethod",
    "CollisionMode",
    "Controller",
    "ControllerMode",
    "ControllerParams",
    "DataMonitor",
    "DifferentialController",
    "DoorState",
    "DropAction",
    "DropPhase",
    "EventBus",
    "FleetKpis",
    "GridSpawnParams",
    "IKParams",
    "JointAction",
    "KinematicController",
    "KpiCollector",
    "LazyLogger",
    "MotionMode",
    "MoveAction",
    "MovementDirection",
    "MultiRobotSimulationCore",
    "NamedLazyLogger",
    "OmniController",
    "Path",
    "PatrolController",
    "PickAction",
    "PickPhase",
    "Pose",
    "PoseAction",
    "PosePhase",
    "RandomWalkController",
    "RobotKpis",
    "ShapeParams",
    "SimEvents",
    "SimObject",
    "SimObjectManager",
    "SimObjectSpawnParams",
    "SimPlugin",
    "SimulationParams",
    "SimulationRecorder",
    "SpatialHashCellSizeMode",
    "WaitAction",
    "WorldLoadError",
    "WorldLoadFailure",
    "add_model_search_path",
    "create_controller",
    "dataclass_from_dict",
    "forward_spawn_params",
    "get_lazy_logger",
    "get_named_lazy_logger",
    "list_model_search_paths",
    "list_models",
    "load_config",
    "load_yaml_config",
    "merge_configs",
    "register_controller",
    "register_entity_class",
    "register_model",
    "remove_model_search_path",
    "resolve_class",
    "resolve_model",
    "wrap_existing_logger",
]
