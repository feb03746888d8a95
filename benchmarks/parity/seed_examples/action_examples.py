"""Seed examples of pybullet_fleet.action (Move, Joint, Pose, Wait, Pick and Drop actions).

Each snippet is the seed's code, in a minimal scene (headless: gui=False, target_rtf=0); names the
seed leaves to the reader (agent, pallet, ...) are created first. Then the sim runs until the
agent's queue is empty, and the trace records what the actions did.
"""

import numpy as np
import pybullet
from parity_trace import Trace
from pybullet_fleet.action import (
    DropAction,
    JointAction,
    MoveAction,
    PickAction,
    PoseAction,
    WaitAction,
)
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject
from pybullet_fleet.types import MovementDirection

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])
sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))


def run_queue(agent, actions, max_steps=800):
    start = sim.step_count
    for _ in range(max_steps):
        sim.step_once()
        if agent.is_action_queue_empty():
            break
    return {
        "steps": sim.step_count - start,
        "statuses": [a.status for a in actions],
        "errors": [a.error_message for a in actions],
        "pose": [round(v, 3) for v in agent.get_pose().position],
    }


def mobile(x=0.0, y=0.0):
    return Agent.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(x, y, 0.1), sim_core=sim
    )


with T.probe("MoveAction") as out:
    agent = mobile()
    # Move forward (normal)
    path = Path.from_positions([[0, 0, 0], [1, 0, 0], [1, 1, 0]])
    action = MoveAction(path=path)
    agent.add_action(action)
    # Move backward
    action2 = MoveAction(path=path, direction=MovementDirection.BACKWARD)
    agent.add_action(action2)
    out.update(run_queue(agent, [action, action2]))
with T.probe("JointAction_scalar") as out:
    agent = Agent.from_urdf(
        "robots/arm_robot.urdf", pose=Pose.from_xyz(5, 5, 0), use_fixed_base=True, sim_core=sim
    )
    # Scalar tolerance (same for all joints)
    action = JointAction(target_joint_positions=[0.0, 1.0, 0.0, 0.0])
    agent.add_action(action)
    out.update(run_queue(agent, [action]))
    out["tolerance_resolved"] = action.tolerance
with T.probe("JointAction_per_joint_tolerance") as out:
    # The seed does not name the robot; rail_joint / elbow_to_wrist are joints of the
    # incumbent's rail arm.
    agent = Agent.from_urdf(
        "robots/rail_arm_robot.urdf", pose=Pose.from_xyz(8, 5, 0), use_fixed_base=True, sim_core=sim
    )
    # Per-joint tolerance for mixed prismatic/revolute
    action = JointAction(
        target_joint_positions={"rail_joint": 0.5, "elbow_to_wrist": -0.3},
        tolerance={"rail_joint": 0.005, "elbow_to_wrist": 0.05},  # 5 mm / 0.05 rad
    )
    agent.add_action(action)
    out.update(run_queue(agent, [action]))
with T.probe("PoseAction") as out:
    agent = Agent.from_urdf(
        "robots/arm_robot.urdf", pose=Pose.from_xyz(0, 0, 0), use_fixed_base=True, sim_core=sim
    )
    action = PoseAction(target_position=[0.3, 0.0, 0.5])
    agent.add_action(action)
    action2 = PoseAction(
        target_position=[0.3, 0.0, 0.5],
        target_orientation=[0, 0, 0, 1],
    )
    agent.add_action(action2)
    out.update(run_queue(agent, [action, action2]))
with T.probe("WaitAction") as out:
    agent = mobile(0, -5)
    # Wait for 5 seconds (charging)
    action = WaitAction(duration=5.0, action_type="charge")
    agent.add_action(action)
    out.update(run_queue(agent, [action]))
    out["times"] = [action.start_time, action.end_time]
with T.probe("PickAction") as out:
    agent = mobile(0, 10)
    pallet = SimObject.from_mesh(
        visual_shape=BOX,
        collision_shape=BOX,
        pose=Pose.from_xyz(3, 10, 0.1),
        pickable=True,
        sim_core=sim,
    )
    # Pick specific object with position offset (using link index)
    action = PickAction(
        target_object_id=pallet.body_id,
        approach_offset=1.0,
        pick_offset=0.3,
        attach_link=-1,  # Base link
        attach_relative_pose=Pose.from_euler(0.6, 0, -0.2, roll=np.pi / 2, pitch=0, yaw=0),
    )
    agent.add_action(action)
    out.update(run_queue(agent, [action]))
    out["pallet"] = [round(v, 3) for v in pallet.get_pose().position]
with T.probe("PickAction_link_name") as out:
    agent = Agent.from_urdf(
        "robots/mobile_robot.urdf", pose=Pose.from_xyz(0, 15, 0.05), sim_core=sim
    )
    pallet = SimObject.from_mesh(
        visual_shape=BOX,
        collision_shape=BOX,
        pose=Pose.from_xyz(3, 15, 0.1),
        pickable=True,
        sim_core=sim,
    )
    # Pick using link name
    action = PickAction(
        target_object_id=pallet.body_id,
        attach_link="sensor_mast",  # Attach to named link
        attach_relative_pose=Pose.from_euler(0, 0, 0.5),
    )
    agent.add_action(action)
    out.update(run_queue(agent, [action]))
    out["pallet_attached"] = pallet.is_attached()
with T.probe("PickAction_nearest") as out:
    agent = mobile(0, 20)
    SimObject.from_mesh(
        visual_shape=BOX,
        collision_shape=BOX,
        pose=Pose.from_xyz(5, 0, 0.1),
        pickable=True,
        sim_core=sim,
    )
    # Pick nearest object at location
    action = PickAction(target_position=[5, 0, 0.1], search_radius=0.5)
    agent.add_action(action)
    out.update(run_queue(agent, [action]))
with T.probe("DropAction") as out:
    agent = mobile(10, 0)
    box = SimObject.from_mesh(
        visual_shape=BOX,
        collision_shape=BOX,
        pose=Pose.from_xyz(10, 0, 0.1),
        pickable=True,
        sim_core=sim,
    )
    agent.attach_object(box)
    # Drop at specific location
    action = DropAction(drop_pose=Pose(position=[10, 5, 0.1]), place_gently=True)
    agent.add_action(action)
    # Drop with specific orientation
    action2 = DropAction(
        drop_pose=Pose(position=[10, 5, 0.1], orientation=[0, 0, 0.7, 0.7]),
    )
    out.update(run_queue(agent, [action]))
    out["box"] = [round(v, 3) for v in box.get_pose().position]
    out["second_orientation"] = action2.drop_pose.orientation
pybullet.disconnect(physicsClientId=sim.client)
T.dump()
