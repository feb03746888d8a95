"""Patrol controller from a config dict (the incumbent's `wait_time` key): arrival / leave times."""

import math

import pybullet
from parity_trace import Trace
from pybullet_fleet.agent import Agent, AgentSpawnParams
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])
WAYPOINTS = [[2.0, 0.0, 0.1], [2.0, 2.0, 0.1], [0.0, 0.0, 0.1]]


def patrol(name, controller, mode="omnidirectional", steps=200):
    with T.probe(name) as out:
        sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
        params = AgentSpawnParams(
            visual_shape=BOX,
            collision_shape=BOX,
            initial_pose=Pose.from_xyz(0, 0, 0.1),
            motion_mode=mode,
            controller=controller,
        )
        agent = Agent.from_params(params, sim_core=sim)
        sim.initialize_simulation()
        events, at = [], None
        for step in range(1, steps + 1):
            sim.step_once()
            pos = agent.get_pose().position
            here = next(
                (i for i, w in enumerate(WAYPOINTS) if math.dist(pos[:2], w[:2]) < 1e-3), None
            )
            if here != at:
                events.append({"step": step, "at": here})
                at = here
        out["visits"] = events
        pybullet.disconnect(physicsClientId=sim.client)


patrol(
    "wait_time_1s_loop", {"type": "patrol", "waypoints": WAYPOINTS, "loop": True, "wait_time": 1.0}
)
patrol(  # fleet_async's spelling of the key
    "wait_1s_loop_key_wait", {"type": "patrol", "waypoints": WAYPOINTS, "loop": True, "wait": 1.0}
)
patrol("no_wait_noloop", {"type": "patrol", "waypoints": WAYPOINTS, "loop": False})
patrol(
    "list_with_base",
    [
        {"type": "differential", "max_linear_vel": 1.0},
        {"type": "patrol", "waypoints": WAYPOINTS, "loop": False},
    ],
    mode="differential",
)
T.dump()
