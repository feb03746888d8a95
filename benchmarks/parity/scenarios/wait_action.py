"""WaitAction queued alone and after a move: start / end times, steps, queue state, events."""

import pybullet
from parity_trace import Trace
from pybullet_fleet.action import MoveAction, WaitAction
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])


def queue(name, actions, timestep=0.1, max_steps=200):
    with T.probe(name) as out:
        sim = MultiRobotSimulationCore(
            SimulationParams(gui=False, monitor=False, target_rtf=0, timestep=timestep)
        )
        agent = Agent.from_mesh(
            visual_shape=BOX,
            collision_shape=BOX,
            pose=Pose.from_xyz(0, 0, 0.1),
            sim_core=sim,
            motion_mode="omnidirectional",
        )
        agent.add_action_sequence(actions)
        out["queue_size_before"] = agent.get_action_queue_size()
        sim.initialize_simulation()
        done = {}
        for step in range(1, max_steps + 1):
            sim.step_once()
            for i, a in enumerate(actions):
                if a.is_complete() and i not in done:
                    done[i] = step
            if agent.is_action_queue_empty():
                out["queue_empty_step"] = step
                break
        out["actions"] = [
            {
                "type": type(a).__name__,
                "status": a.status,
                "start": a.start_time,
                "end": a.end_time,
                "duration": a.get_duration(),
                "complete_step": done.get(i),
            }
            for i, a in enumerate(actions)
        ]
        out["sim_time"] = sim.sim_time
        pybullet.disconnect(physicsClientId=sim.client)


queue("wait_2s", [WaitAction(duration=2.0, action_type="charge")])
queue("wait_0.25s", [WaitAction(duration=0.25)])
queue("wait_0.25s_dt0.01", [WaitAction(duration=0.25)], timestep=0.01, max_steps=200)
queue("wait_0s", [WaitAction(duration=0.0)])
queue(
    "move_then_wait",
    [MoveAction(path=Path.from_positions([[1.0, 0.0, 0.1]])), WaitAction(duration=1.0)],
)
queue("wait_wait", [WaitAction(duration=0.5), WaitAction(duration=0.5)])
with T.probe("fields") as out:
    w = WaitAction(duration=5.0, action_type="charge")
    out.update(
        duration=w.duration,
        action_type=w.action_type,
        status=w.status,
        start_time=w.start_time,
        end_time=w.end_time,
        error_message=w.error_message,
    )
T.dump()
