"""STATIC objects: never move; ignore_static_collision on / off; set_pose on a static object."""

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject
from pybullet_fleet.types import CollisionMode

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.25, 0.25, 0.1])


def scene(name, ignore_static, modes, nudge=False):
    with T.probe(name) as out:
        sim = MultiRobotSimulationCore(
            SimulationParams(
                gui=False, monitor=False, target_rtf=0, ignore_static_collision=ignore_static
            )
        )
        objs = [
            SimObject.from_mesh(
                visual_shape=BOX,
                collision_shape=BOX,
                pose=Pose.from_xyz(0.3 * i, 0, 0.1),
                sim_core=sim,
                collision_mode=m,
                name=f"o{i}",
            )
            for i, m in enumerate(modes)
        ]
        sim.initialize_simulation()
        if nudge:  # every non-static object moves once (the incumbent only checks moved objects)
            for o in objs:
                if not o.is_static:
                    o.set_pose(Pose.from_xyz(o.get_pose().x, 0.01, 0.1))
        sim.step_once()
        names = {o.object_id: o.name for o in objs}
        out["pairs"] = sorted(
            sorted([names[i], names[j]]) for i, j in sim.get_active_collision_pairs()
        )
        out["is_static"] = [o.is_static for o in objs]
        out["filter_pairs"] = call_safely(
            lambda: len(sim.filter_aabb_pairs(ignore_static=False)[0])
        )
        pybullet.disconnect(physicsClientId=sim.client)


S, N = CollisionMode.STATIC, CollisionMode.NORMAL_3D
scene("static_static_ignore", True, [S, S])
scene("static_static_report", False, [S, S])
scene("static_normal_ignore", True, [S, N])
scene("static_normal_report", False, [S, N])
scene("static_normal_ignore_moved", True, [S, N], nudge=True)
scene("static_normal_report_moved", False, [S, N], nudge=True)
scene("normal_normal_unmoved", True, [N, N])
scene("normal_normal_moved", True, [N, N], nudge=True)
scene("normal_2d_vs_3d_moved", True, [CollisionMode.NORMAL_2D, N], nudge=True)
scene("disabled_moved", True, [CollisionMode.DISABLED, N], nudge=True)
with T.probe("set_pose_on_static") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    wall = SimObject.from_mesh(
        visual_shape=BOX,
        collision_shape=BOX,
        pose=Pose.from_xyz(0, 0, 0.1),
        sim_core=sim,
        collision_mode=S,
    )
    out["outside_step"] = call_safely(wall.set_pose, Pose.from_xyz(1, 0, 0.1))
    out["pose_after"] = wall.get_pose().position
    out["pybullet_pose_after"] = pybullet.getBasePositionAndOrientation(
        wall.body_id, physicsClientId=sim.client
    )[0]
    wall.set_collision_mode(CollisionMode.NORMAL_3D)
    out["after_mode_change"] = call_safely(wall.set_pose, Pose.from_xyz(2, 0, 0.1))
    out["pose_after_mode_change"] = wall.get_pose().position
    out["is_static_now"] = wall.is_static
    pybullet.disconnect(physicsClientId=sim.client)
T.dump()
