"""Callbacks at a frequency: sim, AgentManager and SimObject callbacks, when and with which dt."""

import pybullet
from parity_trace import Trace
from pybullet_fleet.agent_manager import AgentManager
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])


def sim_callbacks(name, freqs, steps=25, timestep=0.1):
    with T.probe(name) as out:
        sim = MultiRobotSimulationCore(
            SimulationParams(gui=False, monitor=False, target_rtf=0, timestep=timestep)
        )
        calls = {str(f): [] for f in freqs}
        for f in freqs:

            def cb(sim_core, dt, key=str(f)):
                calls[key].append([sim_core.step_count, round(sim_core.sim_time, 4), round(dt, 4)])

            sim.register_callback(cb, frequency=f)
        sim.initialize_simulation()
        for _ in range(steps):
            sim.step_once()
        out["calls"] = calls
        pybullet.disconnect(physicsClientId=sim.client)


sim_callbacks("sim_every_step_and_10hz", [None, 10.0])
sim_callbacks("sim_2hz_3hz_4hz", [2.0, 3.0, 4.0])
sim_callbacks("sim_3hz_dt0.05", [3.0], steps=30, timestep=0.05)
sim_callbacks("sim_0.5hz", [0.5], steps=45)
with T.probe("manager_callback") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    mgr = AgentManager(sim_core=sim, update_frequency=5.0)
    calls = []
    mgr.register_callback(
        lambda manager, dt: calls.append(
            [sim.step_count, round(sim.sim_time, 4), round(dt, 4), manager is mgr]
        )
    )
    mgr.register_callback(
        lambda manager, dt: calls.append(["2hz", sim.step_count, round(dt, 4)]), frequency=2.0
    )
    sim.initialize_simulation()
    for _ in range(12):
        sim.step_once()
    out["calls"] = calls
    pybullet.disconnect(physicsClientId=sim.client)
with T.probe("simobject_callback") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    obj = SimObject.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0, 0, 0.1), sim_core=sim
    )
    calls = []
    obj.register_callback(lambda *a: calls.append([sim.step_count, len(a)]), frequency=0.25)
    sim.initialize_simulation()
    for _ in range(12):
        sim.step_once()
    out["calls_during_steps"] = calls[:]
    obj.execute_callbacks(1.0)
    obj.execute_callbacks(1.1)
    obj.execute_callbacks(1.3)
    out["calls_after_manual"] = calls
    pybullet.disconnect(physicsClientId=sim.client)
with T.probe("unregister") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    n = []

    def cb(sim_core, dt):
        n.append(sim_core.step_count)

    sim.register_callback(cb)
    sim.initialize_simulation()
    sim.step_once()
    out["unregister_returns"] = sim.unregister_callback(cb)
    sim.step_once()
    out["calls"] = n
    pybullet.disconnect(physicsClientId=sim.client)
T.dump()
