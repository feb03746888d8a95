"""SimObjectSpawnParams / AgentSpawnParams / ShapeParams .from_dict: required name, pose keys."""

import math

import pybullet
from parity_trace import Trace, angle
from pybullet_fleet.agent import AgentSpawnParams
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject, SimObjectSpawnParams

T = Trace()
BOX = {"shape_type": "box", "half_extents": [0.3, 0.3, 0.1]}


def params(name, cls, config):
    with T.probe(name) as out:
        p = cls.from_dict(config)
        out.update(
            name=p.name,
            position=p.initial_pose.position,
            yaw=angle(p.initial_pose.yaw),
            mass=p.mass,
            pickable=p.pickable,
            collision_mode=p.collision_mode,
            visual=type(p.visual_shape).__name__,
            user_data=p.user_data,
        )


params("no_name", SimObjectSpawnParams, {"visual_shape": BOX, "pose": [1, 2, 0.1]})
params(
    "pose_list", SimObjectSpawnParams, {"name": "box0", "visual_shape": BOX, "pose": [3, 0, 0.1]}
)
params("pose_and_yaw", SimObjectSpawnParams, {"name": "b", "pose": [3, 0, 0.1], "yaw": math.pi / 2})
params(
    "initial_pose_vs_pose",
    SimObjectSpawnParams,
    {"name": "b", "initial_pose": Pose.from_xyz(7, 7, 0), "pose": [1, 1, 0]},
)
params(
    "initial_pose_only", SimObjectSpawnParams, {"name": "b", "initial_pose": Pose.from_xyz(7, 7, 0)}
)
params("collision_mode_str", SimObjectSpawnParams, {"name": "b", "collision_mode": "static"})
params("unknown_key", SimObjectSpawnParams, {"name": "b", "colour": "red"})
params(
    "agent_no_name",
    AgentSpawnParams,
    {"urdf_path": "robots/mobile_robot.urdf", "pose": [0, 0, 0.05]},
)
params(
    "agent_initial_pose_vs_pose",
    AgentSpawnParams,
    {
        "urdf_path": "robots/mobile_robot.urdf",
        "initial_pose": Pose.from_xyz(1, 2, 0),
        "pose": [5, 5, 0],
    },
)
params(
    "agent_controller",
    AgentSpawnParams,
    {"visual_shape": BOX, "controller": {"max_linear_vel": 2.0, "max_linear_accel": 5.0}},
)
with T.probe("shape_from_dict") as out:
    s = ShapeParams.from_dict({"shape_type": "cylinder", "radius": 0.2})
    out.update(
        type=s.shape_type,
        radius=s.radius,
        height=s.height,
        rgba=s.rgba_color,
        half_extents=s.half_extents,
        mesh_scale=s.mesh_scale,
    )
with T.probe("defaults") as out:
    p = SimObjectSpawnParams()
    a = AgentSpawnParams()
    out.update(
        pose=p.initial_pose.position,
        mass=p.mass,
        pickable=p.pickable,
        mode=p.collision_mode,
        agent_motion=a.motion_mode,
        agent_fixed=a.use_fixed_base,
        agent_mass=a.mass,
        agent_pickable=a.pickable,
    )
with T.probe("from_dict_spawn") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    obj = SimObject.from_dict(
        {"name": "box0", "visual_shape": BOX, "collision_shape": BOX, "pose": [3, 0, 0.1]},
        sim_core=sim,
    )
    out.update(name=obj.name, pos=obj.get_pose().position, mass=obj.mass)
    pybullet.disconnect(physicsClientId=sim.client)
T.dump()
