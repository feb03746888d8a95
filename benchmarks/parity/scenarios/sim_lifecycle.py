"""Simulation lifecycle: clock before / after steps, params defaults, two sims, reset, pause."""

import dataclasses

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])
with T.probe("params_defaults") as out:
    out["fields"] = {
        f.name: (f.default if f.default is not dataclasses.MISSING else "<factory>")
        for f in dataclasses.fields(SimulationParams)
    }
with T.probe("params_from_dict") as out:
    out["flat"] = call_safely(
        lambda: SimulationParams.from_dict({"timestep": 0.05, "gui": False}).timestep
    )
    out["unknown_key"] = call_safely(
        lambda: SimulationParams.from_dict({"timestep": 0.05, "gui": False, "tiemstep": 1}).timestep
    )
    out["nested"] = call_safely(
        lambda: SimulationParams.from_dict({"simulation": {"timestep": 0.05}}).timestep
    )
with T.probe("clock") as out:
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, monitor=False, target_rtf=0, timestep=0.1)
    )
    seen = []
    sim.register_callback(lambda s, dt: seen.append([s.step_count, round(s.sim_time, 6)]))
    out["before_init"] = [sim.step_count, sim.sim_time]
    sim.initialize_simulation()
    after = []
    for _ in range(3):
        sim.step_once()
        after.append([sim.step_count, round(sim.sim_time, 6)])
    out["after_each_step"] = after
    out["inside_callback"] = seen
    for _ in range(997):
        sim.step_once()
    out["after_1000_steps"] = [sim.step_count, repr(sim.sim_time)]
    sim.pause()
    sim.step_once()
    out["paused_step"] = [sim.step_count, sim.is_paused]
    sim.resume()
    pybullet.disconnect(physicsClientId=sim.client)
with T.probe("run_simulation") as out:
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, monitor=False, target_rtf=0, timestep=0.1)
    )
    sim.run_simulation(duration=1.0)
    out["after_run_1s"] = [sim.step_count, round(sim.sim_time, 6)]
    out["connected_after_run"] = pybullet.isConnected(physicsClientId=sim.client)
with T.probe("reset") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    calls = []
    sim.register_callback(lambda s, dt: calls.append(s.step_count))
    Agent.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0, 0, 0.1), sim_core=sim
    )
    sim.step_once()
    sim.step_once()
    sim.reset()
    out["after_reset"] = [len(sim.sim_objects), sim.step_count, sim.sim_time]
    sim.step_once()
    out["callback_kept"] = calls
    a = Agent.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0, 0, 0.1), sim_core=sim
    )
    out["new_id"] = a.object_id
    pybullet.disconnect(physicsClientId=sim.client)
with T.probe("two_sims_alive") as out:
    s1 = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    Agent.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0, 0, 0.1), sim_core=s1
    )
    s2 = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    out["clients"] = [s1.client, s2.client]
    out["second_agent"] = call_safely(
        lambda: (
            Agent.from_mesh(
                visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(1, 0, 0.1), sim_core=s2
            ).object_id
        )
    )
T.dump()
