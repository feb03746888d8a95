"""The seed-module facades: ``fleet_async.<module>`` for each module of the reference API.

Each facade offers exactly the names its module documents in the reference API, so
``from pybullet_fleet.agent import Agent`` ports as ``from fleet_async.agent import Agent``.
"""

from __future__ import annotations

import importlib

import pytest

import fleet_async

DOCUMENTED: dict[str, tuple[str, ...]] = {
    "action": (
        "Action",
        "DEFAULT_EE_TOLERANCE",
        "DEFAULT_JOINT_TOLERANCE",
        "DEFAULT_MAX_FORCE",
        "DEFAULT_MOVE_SKIP_THRESHOLD",
        "DropAction",
        "DropPhase",
        "JointAction",
        "MoveAction",
        "PickAction",
        "PickPhase",
        "PoseAction",
        "WaitAction",
    ),
    "agent": (
        "Agent",
        "AgentSpawnParams",
        "IKParams",
    ),
    "agent_manager": (
        "AgentManager",
        "GridSpawnParams",
        "SimObjectManager",
    ),
    "config_utils": (
        "dataclass_from_dict",
        "forward_spawn_params",
        "load_config",
        "load_yaml_config",
        "merge_configs",
        "resolve_class",
    ),
    "core_simulation": (
        "MultiRobotSimulationCore",
        "SimulationParams",
    ),
    "data_monitor": ("DataMonitor",),
    "events": ("EventBus", "SimEvents"),
    "geometry": (
        "Path",
        "Pose",
        "Quat",
        "ScalarOrAxes",
        "SlerpPrecomp",
        "as_axes",
        "clamp_vec_to_limit",
        "is_scalar",
        "projected_axis_limit",
        "quat_angle_between",
        "quat_from_rotvec",
        "quat_multiply",
        "quat_slerp",
        "quat_slerp_batch",
        "quat_slerp_precompute",
        "quat_to_rot_matrix",
        "rotate_vector",
    ),
    "logging_utils": (
        "LazyLogger",
        "NamedLazyLogger",
        "get_lazy_logger",
        "get_named_lazy_logger",
        "lazy_log",
        "wrap_existing_logger",
    ),
    "sim_object": (
        "ShapeParams",
        "SimObject",
        "SimObjectSpawnParams",
    ),
    "tools": (
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
    ),
    "types": (
        "ActionStatus",
        "CollisionDetectionMethod",
        "CollisionMode",
        "ControllerMode",
        "DoorState",
        "MotionMode",
        "MovementDirection",
        "PosePhase",
        "SpatialHashCellSizeMode",
    ),
}
"""Names each reference module documents (``pybullet_fleet.data_monitor.main`` has no
counterpart: fleet_async's monitor window is a child process that DataMonitor feeds), plus
``events``: not in the reference documentation, but its ``SimObject.events`` example and the
incumbent's scripts import ``SimEvents`` from ``pybullet_fleet.events``. ``lazy_log`` is the
decorator the documentation's LazyLogger example uses."""


@pytest.mark.parametrize(("module", "names"), DOCUMENTED.items())
def test_every_documented_name_imports(module, names):
    facade = importlib.import_module(f"fleet_async.{module}")
    namespace: dict[str, object] = {}
    for name in names:
        exec(f"from fleet_async.{module} import {name}", namespace)
    assert sorted(facade.__all__) == sorted(names)


@pytest.mark.parametrize(("module", "names"), DOCUMENTED.items())
def test_facade_names_are_the_package_names(module, names):
    facade = importlib.import_module(f"fleet_async.{module}")
    for name in names:
        if name in fleet_async.__all__:
            assert getattr(facade, name) is getattr(fleet_async, name), name


def test_a_seed_script_ports_by_renaming_its_imports():
    from fleet_async.agent import Agent
    from fleet_async.core_simulation import MultiRobotSimulationCore, SimulationParams
    from fleet_async.geometry import Pose
    from fleet_async.sim_object import ShapeParams

    with MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False)) as sim:
        box = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
        robot = Agent.from_mesh(box, box, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")
        robot.set_goal_pose(Pose.from_xyz(1, 0, 0.1))
        for _ in range(100):
            sim.step_once()
        assert not robot.is_moving
        assert robot.get_pose().position.tolist() == [1.0, 0.0, 0.1]
