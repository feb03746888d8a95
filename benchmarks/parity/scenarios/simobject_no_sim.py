"""SimObject(body_id, sim_core=None): pose, attach / detach with no simulation, add_object."""

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import SimObject


def body(x, client):
    shape = pybullet.createCollisionShape(
        pybullet.GEOM_BOX, halfExtents=[0.1, 0.1, 0.1], physicsClientId=client
    )
    return pybullet.createMultiBody(
        baseMass=0, baseCollisionShapeIndex=shape, basePosition=[x, 0, 0.1], physicsClientId=client
    )


T = Trace()
with T.probe("no_simulation_at_all") as out:
    client = pybullet.connect(pybullet.DIRECT)
    parent = SimObject(body(0, client), sim_core=None)
    child = SimObject(body(2, client), sim_core=None)
    out["object_ids"] = [parent.object_id, child.object_id]
    out["pose"] = parent.get_pose().position
    out["attach"] = call_safely(parent.attach_object, child, relative_pose=Pose.from_xyz(0.5, 0, 0))
    out["attached"] = [o.body_id == child.body_id for o in parent.get_attached_objects()]
    out["child_is_attached"] = child.is_attached()
    out["child_pose_after_attach"] = call_safely(lambda: child.get_pose().position)
    out["set_pose"] = call_safely(parent.set_pose, Pose.from_xyz(1, 0, 0.1))
    out["child_pose_after_parent_move"] = call_safely(lambda: child.get_pose().position)
    out["detach"] = call_safely(parent.detach_object, child, drop_pose=Pose.from_xyz(3, 3, 0.1))
    out["child_pose_after_detach"] = call_safely(lambda: child.get_pose().position)
    out["detach_again"] = call_safely(parent.detach_object, child)
    pybullet.disconnect(physicsClientId=client)
with T.probe("add_object_later") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    obj = SimObject(body(1, sim.client), sim_core=None)
    out["before"] = {"id": obj.object_id, "n": len(sim.sim_objects)}
    out["add_returns"] = call_safely(sim.add_object, obj)
    out["after"] = {"id": obj.object_id, "n": len(sim.sim_objects), "pose": obj.get_pose().position}
    out["set_pose_after_add"] = call_safely(obj.set_pose, Pose.from_xyz(4, 0, 0.1))
    out["pose_after"] = obj.get_pose().position
    pybullet.disconnect(physicsClientId=sim.client)
T.dump()
