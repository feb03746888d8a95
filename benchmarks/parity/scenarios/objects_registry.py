"""sim_core.objects, _sim_objects_dict, sim_objects, agents, get_object_by_id, ids and names."""

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])
sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
a = Agent.from_mesh(
    visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0, 0, 0.1), sim_core=sim, name="A"
)
o = SimObject.from_mesh(
    visual_shape=BOX,
    collision_shape=BOX,
    pose=Pose.from_xyz(2, 0, 0.1),
    sim_core=sim,
    name="Pallet_A",
)
u = SimObject.from_mesh(
    visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(4, 0, 0.1), sim_core=sim
)
with T.probe("ids") as out:
    out.update(
        object_ids=[a.object_id, o.object_id, u.object_id],
        body_ids=[a.body_id, o.body_id, u.body_id],
        names=[a.name, o.name, u.name],
    )
with T.probe("collections") as out:
    out["sim_objects"] = [x.name for x in sim.sim_objects]
    out["agents"] = [x.name for x in sim.agents]
    out["objects"] = call_safely(lambda: [x.name for x in sim.objects])
    out["objects_filter_example"] = call_safely(
        lambda: len([x for x in sim.objects if x.name == "Pallet_A"])
    )
    out["_sim_objects_dict"] = call_safely(
        lambda: {str(k): v.name for k, v in sim._sim_objects_dict.items()}  # noqa: SLF001  # the seed's example reads it
    )
    out["get_object_by_id"] = call_safely(lambda: sim.get_object_by_id(o.object_id).name)
    out["get_object_by_id_missing"] = call_safely(lambda: sim.get_object_by_id(999))
with T.probe("remove") as out:
    sim.remove_object(o)
    out["sim_objects"] = [x.name for x in sim.sim_objects]
    out["dict_after"] = call_safely(lambda: sorted(sim._sim_objects_dict))  # noqa: SLF001  # as the seed's example
    out["new_id_after_remove"] = SimObject.from_mesh(
        visual_shape=BOX, pose=Pose.from_xyz(6, 0, 0.1), sim_core=sim
    ).object_id
with T.probe("counts") as out:
    out.update(
        step_count=sim.step_count,
        collision_count=sim.collision_count,
        sim_time=sim.sim_time,
        params_timestep=sim.params.timestep,
        is_paused=sim.is_paused,
    )
pybullet.disconnect(physicsClientId=sim.client)
T.dump()
