"""Agent.from_urdf: mass=None keeps the URDF's masses, mass=0.0 kinematic; bundled model names."""

import os

import pybullet
import pybullet_data
from parity_trace import Trace, call_safely
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose

T = Trace()
KUKA = os.path.join(pybullet_data.getDataPath(), "kuka_iiwa", "model.urdf")


def describe(agent, client):
    n = pybullet.getNumJoints(agent.body_id, physicsClientId=client)
    masses = [
        pybullet.getDynamicsInfo(agent.body_id, i, physicsClientId=client)[0] for i in range(-1, n)
    ]
    joints = [pybullet.getJointInfo(agent.body_id, i, physicsClientId=client) for i in range(n)]
    return {
        "link_masses": masses,
        "mass_attr": agent.mass,
        "is_kinematic": call_safely(lambda: agent.is_kinematic),
        "num_joints": agent.get_num_joints(),
        "is_urdf": agent.is_urdf_robot(),
        "get_pose": agent.get_pose().position,
        "pybullet_base": pybullet.getBasePositionAndOrientation(
            agent.body_id, physicsClientId=client
        )[0],
        "joint_names": [j[1].decode() for j in joints],
        "link_names": [j[12].decode() for j in joints],
    }


def load(name, path, **kwargs):
    with T.probe(name) as out:
        sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
        agent = Agent.from_urdf(path, pose=Pose.from_xyz(0, 0, 0), sim_core=sim, **kwargs)
        out.update(describe(agent, sim.client))
        pybullet.disconnect(physicsClientId=sim.client)


load("kuka_mass_default", KUKA, use_fixed_base=True)
load("kuka_mass_None", KUKA, use_fixed_base=True, mass=None)
load("kuka_mass_0", KUKA, use_fixed_base=True, mass=0.0)
for model in (
    "robots/arm_robot.urdf",
    "robots/mobile_robot.urdf",
    "robots/mobile_manipulator.urdf",
    "robots/simple_cube.urdf",
    "arm_robot",
    "mobile_robot",
    "robots/rail_arm_robot.urdf",
):
    load(f"bundled:{model}", model, mass=0.0)
T.dump()
