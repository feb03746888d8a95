"""The Action protocol called directly: `while not a.is_complete(): a.execute(agent, dt)`."""

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.action import MoveAction, WaitAction
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])
DT = 0.1
CAP = 500


def fresh():
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, monitor=False, target_rtf=0, timestep=DT)
    )
    agent = Agent.from_mesh(
        visual_shape=BOX,
        collision_shape=BOX,
        pose=Pose.from_xyz(0, 0, 0.1),
        sim_core=sim,
        motion_mode="omnidirectional",
    )
    return sim, agent


def drive(name, make_action, step_sim=False, update_agent=False):
    """Run the action with the user's own loop; optionally step the sim / agent in between."""
    with T.probe(name) as out:
        sim, agent = fresh()
        action = make_action()
        out["status_before"] = action.status
        results, n = [], 0
        while not action.is_complete() and n < CAP:
            results.append(action.execute(agent, DT))
            if update_agent:
                agent.update(DT)
            if step_sim:
                sim.step_once()
            n += 1
        pose = agent.get_pose()
        out.update(
            iterations=n,
            ended=action.is_complete(),
            status=action.status,
            start_time=action.start_time,
            end_time=action.end_time,
            duration=call_safely(action.get_duration),
            execute_returns=sorted({repr(r) for r in results}),
            first_true=next((i + 1 for i, r in enumerate(results) if r is True), None),
            pose=[pose.x, pose.y],
            sim_time=sim.sim_time,
        )
        action.reset()
        out["after_reset"] = {
            "status": action.status,
            "start": action.start_time,
            "end": action.end_time,
            "complete": action.is_complete(),
        }
        action.cancel()
        out["after_cancel"] = {"status": action.status, "complete": action.is_complete()}
        pybullet.disconnect(physicsClientId=sim.client)


drive("wait_1s_execute_only", lambda: WaitAction(duration=1.0))
drive("wait_1s_with_step", lambda: WaitAction(duration=1.0), step_sim=True)
drive("move_1m_execute_only", lambda: MoveAction(path=Path.from_positions([[1.0, 0.0, 0.1]])))
drive(
    "move_1m_execute_update",
    lambda: MoveAction(path=Path.from_positions([[1.0, 0.0, 0.1]])),
    update_agent=True,
)
drive(
    "move_1m_execute_step",
    lambda: MoveAction(path=Path.from_positions([[1.0, 0.0, 0.1]])),
    step_sim=True,
)
with T.probe("cancel_before_start") as out:
    a = WaitAction(duration=1.0)
    a.cancel()
    out.update(status=a.status, complete=a.is_complete(), end_time=a.end_time)
T.dump()
