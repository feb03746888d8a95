"""The synchronous simulator: state store, step loop, events, objects and the PyBullet adapter.

Its sub-packages are layers that import only downward at run time, from ``base`` up through
``geometry``, ``world``, ``collision``, ``bodies``, ``motion``, ``actions``, ``missions``,
``agents``, ``sim``, ``metrics`` and ``checkpoint``, ``managers`` and ``devices`` to ``scenario``
and ``view``; ``simulation.py`` assembles ``MultiRobotSimulationCore`` on top
(docs/architecture.md). Nothing in ``fleet_async.core`` imports ``fleet_async.tasks``; the async
mission layer sits on top of this package, reaches it through ``fleet_async.core.missions``, and
never inside it.
"""

from fleet_async.core.actions.action import (
    DEFAULT_EE_TOLERANCE,
    DEFAULT_JOINT_TOLERANCE,
    DEFAULT_MAX_FORCE,
    DEFAULT_MOVE_SKIP_THRESHOLD,
    Action,
    MoveAction,
    WaitAction,
)
from fleet_async.core.actions.arm_actions import JointAction, PoseAction
from fleet_async.core.actions.pick_drop import DropAction, PickAction
from fleet_async.core.agents.agent import Agent
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.agents.agent_plugins import AgentPlugin, BatteryPlugin
from fleet_async.core.base.config_utils import (
    dataclass_from_dict,
    forward_spawn_params,
    load_config,
    load_yaml_config,
    merge_configs,
    resolve_class,
)
from fleet_async.core.base.device_events import DeviceEvents
from fleet_async.core.base.events import EventBus, SimEvents
from fleet_async.core.base.logging_utils import (
    LazyLogger,
    NamedLazyLogger,
    get_lazy_logger,
    get_named_lazy_logger,
    wrap_existing_logger,
)
from fleet_async.core.base.params import SimulationParams
from fleet_async.core.base.types import (
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
from fleet_async.core.bodies.models import (
    add_model_search_path,
    list_model_search_paths,
    list_models,
    register_model,
    remove_model_search_path,
    resolve_model,
)
from fleet_async.core.bodies.sim_object import ObjectRemovedError, SimObject
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.checkpoint.format import CheckpointError
from fleet_async.core.collision.safety_params import SafetyFieldParams
from fleet_async.core.devices import (
    DispenseAction,
    Door,
    DoorParams,
    DoorType,
    Elevator,
    ElevatorParams,
    ElevatorRequestPolicy,
    ElevatorRequestResult,
    ElevatorState,
    IngestAction,
    Workcell,
    WorkcellKind,
    WorkcellParams,
    WorkcellPlugin,
)
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.waypoints import Path
from fleet_async.core.managers.agent_manager import AgentManager
from fleet_async.core.managers.grid_spawn import GridSpawnParams
from fleet_async.core.managers.sim_object_manager import SimObjectManager, register_entity_class
from fleet_async.core.maps import GridMap, OccupancyGrid, read_movingai_scen
from fleet_async.core.metrics.kpis import KpiCollector
from fleet_async.core.metrics.rows import FleetKpis, RobotKpis
from fleet_async.core.motion.controllers import (
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
from fleet_async.core.motion.ik import IKParams
from fleet_async.core.routes import (
    FollowRouteAction,
    RouteEdge,
    RouteGraph,
    RouteNode,
    load_route_graph,
)
from fleet_async.core.scenario.world_loader import WorldLoadError, WorldLoadFailure
from fleet_async.core.sim.plugins import SimPlugin
from fleet_async.core.simulation import MultiRobotSimulationCore
from fleet_async.core.view.monitor import DataMonitor
from fleet_async.core.view.recording import SimulationRecorder
from fleet_async.core.world.shapes import ShapeParams

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
    "DeviceEvents",
    "DifferentialController",
    "DispenseAction",
    "Door",
    "DoorParams",
    "DoorState",
    "DoorType",
    "DropAction",
    "DropPhase",
    "Elevator",
    "ElevatorParams",
    "ElevatorRequestPolicy",
    "ElevatorRequestResult",
    "ElevatorState",
    "EventBus",
    "FleetKpis",
    "FollowRouteAction",
    "GridMap",
    "GridSpawnParams",
    "IKParams",
    "IngestAction",
    "JointAction",
    "KinematicController",
    "KpiCollector",
    "LazyLogger",
    "MotionMode",
    "MoveAction",
    "MovementDirection",
    "MultiRobotSimulationCore",
    "NamedLazyLogger",
    "ObjectRemovedError",
    "OccupancyGrid",
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
    "RouteEdge",
    "RouteGraph",
    "RouteNode",
    "SafetyFieldParams",
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
    "Workcell",
    "WorkcellKind",
    "WorkcellParams",
    "WorkcellPlugin",
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
    "load_route_graph",
    "load_yaml_config",
    "merge_configs",
    "read_movingai_scen",
    "register_controller",
    "register_entity_class",
    "register_model",
    "remove_model_search_path",
    "resolve_class",
    "resolve_model",
    "wrap_existing_logger",
]
