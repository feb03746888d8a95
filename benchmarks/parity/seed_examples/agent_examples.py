"""Seed examples of pybullet_fleet.agent (spawn params, factories, joints, IK, action queue).

Files the seed names but does not ship ('robot.obj', 'arm.urdf') are stood in for: a small OBJ
box is written to the working directory; 'arm.urdf' is read as the bundled arm_robot.urdf.
"""

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.action import DropAction, MoveAction, PickAction, WaitAction
from pybullet_fleet.agent import Agent, AgentSpawnParams, IKParams
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject

T = Trace()
with open("robot.obj", "w") as fh:  # stand-in for the seed's mesh
    fh.write(
        "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\nv 0 0 0.5\n"
        "f 1 2 3\nf 1 3 4\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n"
    )
sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))


def summary(robot):
    p = robot.get_pose()
    return {
        "pos": [round(v, 3) for v in p.position],
        "mode": robot.motion_mode,
        "joints": robot.get_num_joints(),
        "max_linear_vel": robot.max_linear_vel,
        "fixed": getattr(robot, "use_fixed_base", None),
    }


with T.probe("AgentSpawnParams.from_dict_mesh") as out:
    config = {
        "visual_shape": ShapeParams(
            shape_type="mesh",
            mesh_path="robot.obj",
            mesh_scale=[1.0, 1.0, 1.0],
            rgba_color=[0.2, 0.2, 0.2, 1.0],
        ),
        "collision_shape": ShapeParams(shape_type="box", half_extents=[0.2, 0.1, 0.2]),
        "initial_pose": Pose.from_xyz(1.0, 2.0, 0.0),
        "controller": {"max_linear_vel": 2.0, "max_linear_accel": 5.0},
        "use_fixed_base": False,
    }
    params = AgentSpawnParams.from_dict(config)
    out["params"] = {"pose": params.initial_pose.position, "fixed": params.use_fixed_base}
with T.probe("AgentSpawnParams.from_dict_urdf") as out:
    # Or for URDF:
    config = {
        "urdf_path": "robots/mobile_robot.urdf",
        "initial_pose": Pose.from_xyz(1.0, 2.0, 0.0),
        "use_fixed_base": False,
    }
    params = AgentSpawnParams.from_dict(config)
    out["params"] = {"urdf": params.urdf_path, "pose": params.initial_pose.position}
with T.probe("IKParams") as out:
    cfg = IKParams(max_outer_iterations=10, seed_quartiles=(0.1, 0.5, 0.9))
    arm = Agent.from_urdf("robots/arm_robot.urdf", ik_params=cfg, sim_core=sim)  # seed: "arm.urdf"
    # Mobile manipulator — solve only for arm joints
    cfg = IKParams(
        ik_joint_names=(
            "mount_to_shoulder",
            "shoulder_to_elbow",
            "elbow_to_wrist",
            "wrist_to_end",
        )
    )
    robot = Agent.from_urdf("mobile_manipulator.urdf", ik_params=cfg, sim_core=sim)
    out.update(arm=arm.ik_params.max_outer_iterations, robot=list(robot.ik_params.ik_joint_names))
with T.probe("from_params_mesh_omni") as out:
    params = AgentSpawnParams(
        visual_shape=ShapeParams(
            shape_type="mesh",
            mesh_path="robot.obj",
            mesh_scale=[1.0, 1.0, 1.0],
            rgba_color=[0.2, 0.2, 0.2, 1.0],
        ),
        collision_shape=ShapeParams(shape_type="box", half_extents=[0.2, 0.1, 0.2]),
        initial_pose=Pose.from_xyz(1.0, 2.0, 0.0),
        controller={"type": "omni", "max_linear_vel": 3.0},
    )
    robot = Agent.from_params(spawn_params=params)
    out["no_sim_core"] = summary(robot)
    robot2 = Agent.from_params(spawn_params=params, sim_core=sim)  # the same, in the sim
    out["with_sim"] = summary(robot2)
with T.probe("from_params_urdf_fixed") as out:
    params = AgentSpawnParams(
        urdf_path="arm_robot.urdf",
        initial_pose=Pose.from_xyz(0.0, 0.0, 0.0),
        use_fixed_base=True,
    )
    robot = Agent.from_params(spawn_params=params, sim_core=sim)
    out.update(summary(robot))
with T.probe("from_params_virtual") as out:
    params = AgentSpawnParams(
        initial_pose=Pose.from_xyz(0.0, 0.0, 0.0),
        controller={"type": "omni", "max_linear_vel": 2.0},
    )
    virtual_agent = Agent.from_params(spawn_params=params, sim_core=sim)
    virtual_agent.set_goal_pose(Pose.from_xyz(1, 0, 0))
    for _ in range(20):
        sim.step_once()
    out.update(summary(virtual_agent))
with T.probe("from_urdf") as out:
    robot = Agent.from_urdf(urdf_path="arm_robot.urdf", sim_core=sim)
    out["arm_robot"] = summary(robot)
    out["panda"] = call_safely(
        lambda: summary(Agent.from_urdf(urdf_path="panda", use_fixed_base=True, sim_core=sim))
    )
    robot = Agent.from_urdf(urdf_path="arm_robot.urdf", mass=0.0, sim_core=sim)
    out["mass0"] = summary(robot)
with T.probe("joint_tolerance") as out:
    agent = Agent.from_urdf(
        "robots/rail_arm_robot.urdf",
        sim_core=sim,  # the seed elides the model: "..."
        joint_tolerance={"rail_joint": 0.005, "elbow_to_wrist": 0.05},
    )
    out["tolerance"] = agent.joint_tolerance
with T.probe("add_action") as out:
    agent = Agent.from_mesh(
        visual_shape=ShapeParams(shape_type="box", half_extents=[0.2, 0.2, 0.1]),
        pose=Pose.from_xyz(20, 0, 0.1),
        sim_core=sim,
    )
    my_path = Path.from_positions([[21, 0, 0.1]])
    agent.add_action(MoveAction(path=my_path))
    agent.add_action(WaitAction(duration=5.0))
    out["queue"] = agent.get_action_queue_size()
    out["current"] = type(agent.get_current_action()).__name__
with T.probe("add_action_sequence") as out:
    agent = Agent.from_mesh(
        visual_shape=ShapeParams(shape_type="box", half_extents=[0.2, 0.2, 0.1]),
        pose=Pose.from_xyz(30, 0, 0.1),
        sim_core=sim,
    )
    obj = SimObject.from_mesh(
        visual_shape=ShapeParams(shape_type="box", half_extents=[0.1, 0.1, 0.1]),
        pose=Pose.from_xyz(33, 0, 0.1),
        pickable=True,
        sim_core=sim,
    )
    path1 = Path.from_positions([[31, 0, 0.1]])
    path2 = Path.from_positions([[33, 5, 0.1]])
    agent.add_action_sequence(
        [
            MoveAction(path=path1),
            PickAction(target_object_id=obj.body_id),
            MoveAction(path=path2),
            DropAction(drop_pose=Pose(position=[10, 5, 0])),
        ]
    )
    for _ in range(600):
        sim.step_once()
        if agent.is_action_queue_empty():
            break
    out["obj"] = [round(v, 3) for v in obj.get_pose().position]
    out["steps"] = sim.step_count
with T.probe("joints") as out:
    robot = Agent.from_urdf(urdf_path="arm_robot.urdf", use_fixed_base=True, sim_core=sim)
    pos, vel = robot.get_joint_state(0)
    out["state0"] = [pos, vel]
    robot.set_joint_target(0, 1.57)  # Move first joint to 90 degrees
    robot.set_all_joints_targets([0.0, 1.57, -1.57, 0.0])
    # Using list
    robot.set_joints_targets([0.0, 1.57, -1.57, 0.0])
    # Using dict
    out["dict_unknown_names"] = call_safely(
        robot.set_joints_targets, {"joint1": 1.57, "joint2": -1.57}
    )
    for _ in range(30):
        sim.step_once()
    # No args — check last commanded targets with agent's default tolerance
    out["settled"] = robot.are_joints_at_targets()
    # Using list
    out["at_list"] = robot.are_joints_at_targets([0.0, 1.57, -1.57, 0.0], tolerance=0.01)
    # Using dict
    out["at_dict_unknown"] = call_safely(
        robot.are_joints_at_targets, {"joint1": 1.57, "joint2": -1.57}, tolerance=0.01
    )
    out["joints"] = [round(robot.get_joint_state(i)[0], 3) for i in range(robot.get_num_joints())]
with T.probe("move_end_effector") as out:
    arm = Agent.from_urdf(urdf_path="arm_robot.urdf", use_fixed_base=True, sim_core=sim)
    reachable = arm.move_end_effector([0.3, 0.0, 0.5])
    out["reachable"] = reachable
pybullet.disconnect(physicsClientId=sim.client)
T.dump()
