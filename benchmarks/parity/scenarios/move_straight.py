"""MoveAction on a straight 2 m path: steps to arrive, action times, trajectory (omni, diff)."""

import math

import pybullet
from parity_trace import Trace, angle
from pybullet_fleet.action import MoveAction
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams
from pybullet_fleet.types import MotionMode

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])


def move(
    t, name, mode, goal, timestep=0.1, goal_yaw=None, start_yaw=0.0, align=True, max_steps=600
):
    with t.probe(name) as out:
        sim = MultiRobotSimulationCore(
            SimulationParams(gui=False, monitor=False, target_rtf=0, timestep=timestep)
        )
        agent = Agent.from_mesh(
            visual_shape=BOX,
            collision_shape=BOX,
            pose=Pose.from_euler(0, 0, 0.1, yaw=start_yaw),
            sim_core=sim,
            motion_mode=mode,
        )
        out["limits"] = {
            "max_linear_vel": agent.max_linear_vel,
            "max_linear_accel": agent.max_linear_accel,
            "max_angular_vel": agent.max_angular_vel,
            "max_angular_accel": agent.max_angular_accel,
        }
        if goal_yaw is None:
            path = Path.from_positions([goal])
        else:
            path = Path([Pose.from_euler(*goal, yaw=goal_yaw)])
        action = MoveAction(path=path, final_orientation_align=align)
        agent.add_action(action)
        sim.initialize_simulation()
        out["sim_time_before"] = sim.sim_time
        traj, arrive, complete, stopped = [], None, None, None
        for step in range(1, max_steps + 1):
            sim.step_once()
            pose = agent.get_pose()
            traj.append([round(pose.x, 3), round(pose.y, 3), angle(pose.yaw)])
            at_goal = math.dist(pose.position[:2], goal[:2]) < 1e-3
            if at_goal and arrive is None:
                arrive = {"step": step, "sim_time": sim.sim_time, "yaw": angle(pose.yaw, 6)}
            if action.is_complete() and complete is None:
                complete = {"step": step, "sim_time": sim.sim_time}
            if complete and not agent.is_moving and stopped is None:
                stopped = {"step": step, "sim_time": sim.sim_time}
            if complete and stopped and agent.is_action_queue_empty():
                break
        final = agent.get_pose()
        out.update(
            arrive=arrive,
            complete=complete,
            not_moving=stopped,
            status=action.status,
            start_time=action.start_time,
            end_time=action.end_time,
            duration=action.get_duration(),
            step_count=sim.step_count,
            final=[final.x, final.y, angle(final.yaw, 6)],
            trajectory=traj,
        )
        pybullet.disconnect(physicsClientId=sim.client)


move(T, "omni_2m_x", MotionMode.OMNIDIRECTIONAL, [2.0, 0.0, 0.1])
move(T, "diff_2m_x", MotionMode.DIFFERENTIAL, [2.0, 0.0, 0.1])
move(
    T,
    "omni_2m_x_dt0.01",
    MotionMode.OMNIDIRECTIONAL,
    [2.0, 0.0, 0.1],
    timestep=0.01,
    max_steps=6000,
)
move(T, "diff_2m_x_dt0.01", MotionMode.DIFFERENTIAL, [2.0, 0.0, 0.1], timestep=0.01, max_steps=6000)
move(T, "omni_10m_x", MotionMode.OMNIDIRECTIONAL, [10.0, 0.0, 0.1])
move(T, "omni_0.3m_x", MotionMode.OMNIDIRECTIONAL, [0.3, 0.0, 0.1])
# Goal to the side: differential has to turn first.
move(T, "diff_2m_y", MotionMode.DIFFERENTIAL, [0.0, 2.0, 0.1])
# Goal yaw differs from the start yaw: "add final rotation ... after reaching the position".
move(
    T,
    "omni_2m_x_goalyaw90_align",
    MotionMode.OMNIDIRECTIONAL,
    [2.0, 0.0, 0.1],
    goal_yaw=math.pi / 2,
)
move(
    T,
    "omni_2m_x_goalyaw90_noalign",
    MotionMode.OMNIDIRECTIONAL,
    [2.0, 0.0, 0.1],
    goal_yaw=math.pi / 2,
    align=False,
)
move(T, "diff_2m_x_goalyaw90_align", MotionMode.DIFFERENTIAL, [2.0, 0.0, 0.1], goal_yaw=math.pi / 2)
move(
    T,
    "diff_2m_x_goalyaw90_noalign",
    MotionMode.DIFFERENTIAL,
    [2.0, 0.0, 0.1],
    goal_yaw=math.pi / 2,
    align=False,
)
T.dump()
