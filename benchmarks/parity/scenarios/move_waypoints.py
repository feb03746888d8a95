"""MoveAction on multi-waypoint paths (omni / diff, final_orientation_align on / off, backward)."""

import math

import pybullet
from parity_trace import Trace, angle
from pybullet_fleet.action import MoveAction
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams
from pybullet_fleet.types import MotionMode, MovementDirection

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])
SQUARE = [[1.0, 0.0, 0.1], [1.0, 1.0, 0.1], [0.0, 1.0, 0.1]]


def follow(name, mode, path, align=True, direction=None, max_steps=800):
    with T.probe(name) as out:
        sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
        agent = Agent.from_mesh(
            visual_shape=BOX,
            collision_shape=BOX,
            pose=Pose.from_xyz(0, 0, 0.1),
            sim_core=sim,
            motion_mode=mode,
        )
        kwargs = {} if direction is None else {"direction": direction}
        action = MoveAction(path=path, final_orientation_align=align, **kwargs)
        agent.add_action(action)
        sim.initialize_simulation()
        targets = [w.position for w in path.waypoints]
        reached, traj, complete = [], [], None
        for step in range(1, max_steps + 1):
            sim.step_once()
            pose = agent.get_pose()
            traj.append([round(pose.x, 3), round(pose.y, 3), angle(pose.yaw)])
            k = len(reached)
            if k < len(targets) and math.dist(pose.position[:2], targets[k][:2]) < 1e-3:
                reached.append({"waypoint": k, "step": step, "yaw": angle(pose.yaw, 6)})
            if action.is_complete():
                complete = {"step": step, "sim_time": sim.sim_time}
                break
        final = agent.get_pose()
        out.update(
            reached=reached,
            complete=complete,
            status=action.status,
            start_time=action.start_time,
            end_time=action.end_time,
            final=[final.x, final.y, angle(final.yaw, 6)],
            path_length=path.get_total_distance(),
            trajectory=traj,
        )
        pybullet.disconnect(physicsClientId=sim.client)


square = Path.from_positions(SQUARE)
yawed = Path(
    [Pose.from_euler(*p, yaw=0.0) for p in SQUARE[:-1]]
    + [Pose.from_euler(*SQUARE[-1], yaw=math.pi)]
)
for mode, tag in ((MotionMode.OMNIDIRECTIONAL, "omni"), (MotionMode.DIFFERENTIAL, "diff")):
    follow(f"{tag}_square_align", mode, square, align=True)
    follow(f"{tag}_square_noalign", mode, square, align=False)
    follow(f"{tag}_square_lastyaw180_align", mode, yawed, align=True)
    follow(f"{tag}_square_lastyaw180_noalign", mode, yawed, align=False)
follow(
    "diff_backward",
    MotionMode.DIFFERENTIAL,
    Path.from_positions([[-2.0, 0.0, 0.1]]),
    direction=MovementDirection.BACKWARD,
)
follow(
    "diff_backward_str",
    MotionMode.DIFFERENTIAL,
    Path.from_positions([[2.0, 0.0, 0.1]]),
    direction="backward",
)
follow(
    "circle_omni",
    MotionMode.OMNIDIRECTIONAL,
    Path.create_circle(center=[2.0, 0.0, 0.1], radius=1.0, num_points=8),
)
T.dump()
