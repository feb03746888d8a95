"""Fixed-base arm: goals ignored; JointAction -> PickAction -> DropAction on the end effector."""

import os

import pybullet
import pybullet_data
from parity_trace import Trace, call_safely
from pybullet_fleet.action import DropAction, JointAction, MoveAction, PickAction
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject

T = Trace()
KUKA = os.path.join(pybullet_data.getDataPath(), "kuka_iiwa", "model.urdf")
CUBE = ShapeParams(shape_type="box", half_extents=[0.03, 0.03, 0.03])


def scene():
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    arm = Agent.from_urdf(
        KUKA, pose=Pose.from_xyz(0, 0, 0), use_fixed_base=True, mass=0.0, sim_core=sim
    )
    cube = SimObject.from_mesh(
        visual_shape=CUBE,
        collision_shape=CUBE,
        pose=Pose.from_xyz(0.5, 0, 0.05),
        pickable=True,
        sim_core=sim,
        name="cube",
    )
    return sim, arm, cube


def run(name, make, steps=300):
    with T.probe(name) as out:
        sim, arm, cube = scene()
        actions = make(arm, cube)
        arm.add_action_sequence(actions)
        sim.initialize_simulation()
        for step in range(1, steps + 1):
            sim.step_once()
            if arm.is_action_queue_empty():
                out["queue_empty_step"] = step
                break
        base = arm.get_pose()
        out.update(
            actions=[
                {
                    "type": type(a).__name__,
                    "status": a.status,
                    "start": a.start_time,
                    "end": a.end_time,
                    "error": a.error_message,
                }
                for a in actions
            ],
            base=[base.x, base.y, base.z],
            cube_attached=cube.is_attached(),
            cube=[round(v, 3) for v in cube.get_pose().position],
            joints=[round(arm.get_joint_state(i)[0], 3) for i in range(arm.get_num_joints())],
        )
        pybullet.disconnect(physicsClientId=sim.client)


TARGET = [0.0, 0.6, 0.0, -1.2, 0.0, 0.6, 0.0]
run(
    "joint_then_pick",
    lambda arm, cube: [
        JointAction(target_joint_positions=TARGET),
        PickAction(target_object_id=cube.body_id, attach_link=6, use_approach=False),
    ],
)
run(
    "joint_pick_drop",
    lambda arm, cube: [
        JointAction(target_joint_positions=TARGET),
        PickAction(target_object_id=cube.body_id, attach_link="lbr_iiwa_link_7"),
        JointAction(target_joint_positions=[0.5, 0.6, 0.0, -1.2, 0.0, 0.6, 0.0]),
        DropAction(drop_pose=Pose.from_xyz(0.4, 0.3, 0.05)),
    ],
)
run(
    "move_on_fixed_base",
    lambda arm, cube: [
        MoveAction(path=Path.from_positions([[1.0, 0.0, 0.0]])),
        JointAction(target_joint_positions=TARGET),
    ],
)
with T.probe("set_goal_pose_fixed") as out:
    sim, arm, cube = scene()
    out["returns"] = call_safely(arm.set_goal_pose, Pose.from_xyz(1, 0, 0))
    out["is_moving"] = arm.is_moving
    out["goal"] = None if arm.goal_pose is None else arm.goal_pose.position
    sim.step_once()
    out["base_after"] = arm.get_pose().position
    pybullet.disconnect(physicsClientId=sim.client)
T.dump()
