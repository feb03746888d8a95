"""Seed examples of pybullet_fleet.tools (doctest-style examples, offset poses, find_nearest)."""

import math

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject
from pybullet_fleet.tools import (
    body_to_world_velocity_2d,
    body_to_world_velocity_3d,
    calculate_offset_pose,
    find_nearest,
    grid_execution,
    normalize_vector_param,
    resolve_joint_index,
    resolve_link_index,
)
from scipy.spatial.transform import Rotation

T = Trace()
with T.probe("velocity") as out:
    out["2d"] = body_to_world_velocity_2d(1.0, 0.0, yaw=math.pi / 2)  # seed: (0.0, 1.0)
    q = Rotation.from_euler("z", 90, degrees=True).as_quat()  # xyzw
    out["3d"] = body_to_world_velocity_3d(1.0, 0.0, 0.0, tuple(q))  # seed: (0.0, 1.0, 0.0)
with T.probe("normalize_vector_param") as out:
    out["scalar"] = normalize_vector_param(2.0, "max_vel", 3)
    out["list"] = normalize_vector_param([1.0, 2.0, 3.0], "max_vel", 3)
with T.probe("offset_pose") as out:
    # Approach pose (1.5m away from target)
    approach = calculate_offset_pose([5, 0, 0.1], [0, 0, 0.3], offset=1.5)
    # Pick pose (0.3m away from target)
    pick = calculate_offset_pose([5, 0, 0.1], [0, 0, 0.3], offset=0.3)
    # At target position (0m offset)
    drop = calculate_offset_pose([5, 0, 0.1], [0, 0, 0.3], offset=0.0)
    out["poses"] = [[round(v, 3) for v in p.position] for p in (approach, pick, drop)]
with T.probe("grid_execution") as out:
    seen = []
    grid_execution(
        grid_num=[2, 2, 1],
        spacing=[1.0, 2.0, 1.0],
        func=lambda idx, pos, **kw: seen.append([idx, pos]),
    )
    out["calls"] = seen
sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
with T.probe("resolve_index") as out:
    robot = SimObject(
        pybullet.loadURDF(
            "r2d2.urdf"
            if False
            else __import__("os").path.join(__import__("pybullet_data").getDataPath(), "r2d2.urdf"),
            physicsClientId=sim.client,
        ),
        sim_core=sim,
    )
    out["link"] = call_safely(resolve_link_index, robot.body_id, "head")
    out["link_int"] = call_safely(resolve_link_index, robot.body_id, 2)
    out["base"] = call_safely(resolve_link_index, robot.body_id, "base_link")
    out["joint"] = call_safely(resolve_joint_index, robot.body_id, "head_swivel")
    out["joint_missing"] = call_safely(resolve_joint_index, robot.body_id, "nope")
    out["link_missing"] = call_safely(resolve_link_index, robot.body_id, "nope")
with T.probe("find_nearest") as out:
    box = ShapeParams(shape_type="box", half_extents=[0.1, 0.1, 0.1])
    agent = SimObject.from_mesh(
        visual_shape=box, pose=Pose.from_xyz(0, 0, 0.1), sim_core=sim, name="agent"
    )
    SimObject.from_mesh(
        visual_shape=box, pose=Pose.from_xyz(5.5, 0, 0.1), sim_core=sim, name="far", pickable=True
    )
    SimObject.from_mesh(
        visual_shape=box, pose=Pose.from_xyz(4.5, 0, 0.1), sim_core=sim, name="near", pickable=True
    )
    sim_core = sim
    # Find nearest pickable, unattached object from a world position
    obj = find_nearest(
        sim_core.sim_objects,
        position=[5, 0, 0],
        search_radius=2.0,
        predicate=lambda o: o.pickable and not o.is_attached(),
        exclude=agent,
    )
    out["found"] = obj.name if obj else None
    out["nearest_pickable"] = call_safely(
        lambda: agent.find_nearest_pickable(search_radius=5.0).name
    )
pybullet.disconnect(physicsClientId=sim.client)
T.dump()
