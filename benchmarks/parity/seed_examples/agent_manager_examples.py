"""Seed examples of pybullet_fleet.agent_manager (grid params, bulk helpers, callbacks, camera)."""

import numpy as np
import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.action import DropAction, MoveAction, PickAction
from pybullet_fleet.agent import AgentSpawnParams
from pybullet_fleet.agent_manager import AgentManager, GridSpawnParams, SimObjectManager
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject, SimObjectSpawnParams

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.2, 0.1])
sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))


def run(n):
    for _ in range(n):
        sim.step_once()


with T.probe("GridSpawnParams.from_dict") as out:
    explicit = GridSpawnParams.from_dict(
        {
            "x_min": 0,
            "x_max": 9,
            "y_min": 0,
            "y_max": 4,
            "spacing": [3.0, 3.0, 0.0],
            "offset": [0, 0, 0.05],
        }
    )
    count = GridSpawnParams.from_dict(
        {"count": 50, "spacing": [3.0, 3.0], "offset": [0, 0, 0.05], "columns": 10}
    )
    out.update(explicit=explicit.total_cells, count=[count.x_max, count.y_max, count.total_cells])
manager = AgentManager(sim_core=sim)
grid = GridSpawnParams(
    x_min=0, x_max=3, y_min=0, y_max=0, spacing=[2.0, 2.0, 0.0], offset=[0, 0, 0.1]
)
manager.spawn_agents_grid(
    4, grid, AgentSpawnParams(visual_shape=BOX, collision_shape=BOX, motion_mode="omnidirectional")
)
with T.probe("set_pose_all") as out:
    # Shift every object 1 m along X
    manager.set_pose_all(
        lambda obj: Pose.from_xyz(
            obj.get_pose().x + 1.0,
            obj.get_pose().y,
            obj.get_pose().z,
        )
    )
    out["x"] = [round(a.get_pose().x, 3) for a in manager.objects]
with T.probe("spawn_grid_mixed") as out:
    mgr = SimObjectManager(sim_core=sim)
    typeA_params = SimObjectSpawnParams(visual_shape=BOX, name="A")
    typeB_params = SimObjectSpawnParams(visual_shape=BOX, name="B")
    grid_params = GridSpawnParams(
        x_min=0, x_max=9, y_min=10, y_max=19, spacing=[1, 1, 0], offset=[0, 0, 0]
    )
    # Spawn 100 objects: 60% typeA, 30% typeB, 10% empty
    spawn_params_list = [
        (typeA_params, 0.6),
        (typeB_params, 0.3),
    ]
    spawned = mgr.spawn_grid_mixed(100, grid_params, spawn_params_list)
    out["count"] = len(spawned)  # random: the seed does not say how it is seeded
    out["types"] = sorted({o.name for o in spawned})
with T.probe("set_goal_pose_all") as out:
    for robot in manager.objects:
        robot.user_data["home_position"] = Pose.from_xyz(robot.get_pose().x, 5, 0.1)

    # Set all agents to move to their designated home positions
    def get_home_goal(robot):
        return robot.user_data["home_position"]

    manager.set_goal_pose_all(get_home_goal)

    # Move all agents 5 meters forward from their current position
    def move_forward(robot):
        current_pos = robot.get_pose().position
        return Pose.from_xyz(current_pos[0] + 5, current_pos[1], current_pos[2])

    run(40)
    manager.set_goal_pose_all(move_forward)
    run(40)
    out["poses"] = [[round(a.get_pose().x, 3), round(a.get_pose().y, 3)] for a in manager.objects]
    out["moving"] = manager.get_moving_count()
with T.probe("set_joints_targets_all") as out:
    # Set all robot arms to neutral position
    def get_neutral_joints(robot):
        return [0.0, 0.0, 0.0, 0.0]

    out["neutral"] = call_safely(manager.set_joints_targets_all, get_neutral_joints)

    # Set custom positions based on robot index
    def get_custom_joints(robot):
        idx = robot.user_data.get("index", 0)
        return [idx * 0.1, 0.0, 0.0, 0.0]

    out["custom"] = call_safely(manager.set_joints_targets_all, get_custom_joints, max_force=1000.0)
with T.probe("add_action_sequence_all") as out:
    for i, robot in enumerate(manager.objects):
        robot.user_data["target_object"] = SimObject.from_mesh(
            visual_shape=BOX, pose=Pose.from_xyz(3 * i, -4, 0.1), pickable=True, sim_core=sim
        )

    def create_pick_drop_sequence(robot):
        target = robot.user_data["target_object"]
        return [
            PickAction(target_object_id=target.body_id),
            MoveAction(path=Path.from_positions([[10, 10, 0]])),
            DropAction(drop_pose=Pose(position=[10, 10, 0])),
        ]

    # Apply to all agents at once
    manager.add_action_sequence_all(create_pick_drop_sequence)
    run(400)
    out["queues_empty"] = [a.is_action_queue_empty() for a in manager.objects]
    out["dropped"] = [
        [round(v, 2) for v in a.user_data["target_object"].get_pose().position]
        for a in manager.objects
    ]
with T.probe("add_action_all") as out:
    for robot in manager.objects:
        robot.user_data["next_position"] = [robot.get_pose().x, 20, 0.1]

    def create_move_action(robot):
        goal_pos = robot.user_data["next_position"]
        return MoveAction(path=Path.from_positions([goal_pos]))

    manager.add_action_all(create_move_action)
    run(200)
    out["y"] = [round(a.get_pose().y, 3) for a in manager.objects]
with T.probe("register_callback") as out:
    calls = []

    def calculate_next_goal(agent):
        return Pose.from_xyz(agent.get_pose().x, agent.get_pose().y + 1, 0.1)

    def goal_update_logic(manager, dt):
        calls.append(round(dt, 3))
        for agent in manager.objects:
            if not agent.is_moving:
                # Set new goal for stopped agents
                new_goal = calculate_next_goal(agent)
                agent.set_goal_pose(new_goal)

    manager.register_callback(goal_update_logic, frequency=4.0)

    def state_tracker(manager, dt):
        for agent in manager.objects:
            # Track agent statistics
            if "total_distance" not in agent.user_data:
                agent.user_data["total_distance"] = 0.0
            agent.user_data["total_distance"] += np.linalg.norm(agent.velocity) * dt

    manager.register_callback(state_tracker, frequency=10.0)
    run(20)
    out["calls"] = calls
    out["distance"] = [round(a.user_data["total_distance"], 3) for a in manager.objects]
with T.probe("setup_camera") as out:
    # Basic usage with default settings
    out["default"] = call_safely(manager.setup_camera)
    # With custom camera config
    camera_config = {
        "camera_mode": "auto",
        "camera_view_type": "top_down",
        "camera_auto_scale": 0.8,
    }
    out["custom"] = call_safely(manager.setup_camera, camera_config)
pybullet.disconnect(physicsClientId=sim.client)
T.dump()
