"""step_once(return_profiling=True) keys, last_profiling, record_profiling, collision off."""

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])


def keys(d):
    if not isinstance(d, dict):
        return repr(type(d).__name__)
    return {k: (keys(v) if isinstance(v, dict) else type(v).__name__) for k, v in d.items()}


def as_dict(m):
    return (
        None if m is None else {k: (as_dict(v) if hasattr(v, "items") else v) for k, v in m.items()}
    )


sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
agent = Agent.from_mesh(
    visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0, 0, 0.1), sim_core=sim
)
sim.initialize_simulation()
with T.probe("plain_step") as out:
    out["returns"] = repr(sim.step_once())
    out["last_profiling"] = call_safely(lambda: as_dict(sim.last_profiling))
with T.probe("profiled_step") as out:
    prof = sim.step_once(return_profiling=True)
    out["keys"] = keys(prof)
    out["all_floats_ms"] = all(
        isinstance(v, float) and v >= 0 for v in prof.values() if not isinstance(v, dict)
    )
    out["last_profiling_keys"] = call_safely(lambda: keys(as_dict(sim.last_profiling)))
    out["last_profiling_read_only"] = call_safely(lambda: sim.last_profiling.__setitem__("x", 1))
with T.probe("collision_off") as out:
    sim.set_collision_check_frequency(0)
    out["keys"] = keys(sim.step_once(return_profiling=True))
with T.probe("custom_field") as out:
    sim.set_collision_check_frequency(None)

    def cb(sim_core, dt):
        sim_core.record_profiling("custom_logic", 1.5)
        sim_core.record_profiling("custom_logic", 2.0)

    sim.register_callback(cb)
    prof = sim.step_once(return_profiling=True)
    out["custom_logic"] = prof.get("custom_logic")
    out["keys"] = sorted(prof)
with T.probe("after_unprofiled_step") as out:
    sim.step_once()
    out["last_profiling"] = call_safely(lambda: as_dict(sim.last_profiling))
with T.probe("time_profiling_param") as out:
    s2 = SimulationParams(
        gui=False, monitor=False, enable_time_profiling=True, profiling_interval=2
    )
    out["fields"] = [s2.enable_time_profiling, s2.profiling_interval]
pybullet.disconnect(physicsClientId=sim.client)
T.dump()
