"""Seed examples of pybullet_fleet.sim_object (ShapeParams, spawn params, events, shared shapes,
from_mesh / from_sdf / from_params, collision modes, attach / detach). Mesh files the seed names
('visual.obj', 'collision.obj', 'pallet.obj') are written as small boxes first."""

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject, SimObjectSpawnParams
from pybullet_fleet.types import CollisionMode

T = Trace()
OBJ = (
    "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n"
    "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n"
    "f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
    "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n"
)
for name in ("visual.obj", "collision.obj", "pallet.obj"):
    with open(name, "w") as fh:
        fh.write(OBJ)
sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
sim_core = sim
with T.probe("ShapeParams") as out:
    # Box visual
    visual = ShapeParams(
        shape_type="box", half_extents=[0.5, 0.3, 0.2], rgba_color=[0.8, 0.2, 0.2, 1.0]
    )
    # Mesh collision
    collision = ShapeParams(
        shape_type="mesh", mesh_path="collision.obj", mesh_scale=[1.0, 1.0, 1.0]
    )
    # Sphere with offset
    sphere = ShapeParams(
        shape_type="sphere",
        radius=0.5,
        rgba_color=[0.0, 1.0, 0.0, 1.0],
        frame_pose=Pose.from_xyz(0, 0, 0.5),
    )
    out["ok"] = [visual.shape_type, collision.shape_type, sphere.frame_pose.z]
with T.probe("SimObjectSpawnParams") as out:
    # Box visual + sphere collision with name
    params = SimObjectSpawnParams(
        visual_shape=ShapeParams(
            shape_type="box", half_extents=[0.5, 0.3, 0.2], rgba_color=[1.0, 0.0, 0.0, 1.0]
        ),
        collision_shape=ShapeParams(shape_type="sphere", radius=0.3),
        initial_pose=Pose.from_xyz(0, 0, 1),
        mass=1.0,
        name="Pallet_A",  # Human-readable name (duplicates allowed)
    )
    obj = SimObject.from_params(params, sim_core)
    # Later: Use object_id for unique lookup
    retrieved_obj = call_safely(lambda: sim_core.get_object_by_id(obj.object_id).name)
    out["get_object_by_id"] = retrieved_obj
    # Or filter by name (may return multiple objects)
    out["sim_core.objects"] = call_safely(
        lambda: len([o for o in sim_core.objects if o.name == "Pallet_A"])
    )
with T.probe("events_subclass") as out:
    bumps = []

    class WarehouseRobot(Agent):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            from pybullet_fleet.events import SimEvents

            self.events.on(SimEvents.COLLISION_STARTED, self._on_bump)
            self.events.on(SimEvents.ACTION_COMPLETED, self._on_task_done)

        def _on_bump(self, other, **kwargs):
            bumps.append("bump")

        def _on_task_done(self, action, status, **kwargs):
            bumps.append(getattr(status, "value", status))

    box = ShapeParams(shape_type="box", half_extents=[0.2, 0.2, 0.1])
    robot = WarehouseRobot.from_mesh(
        visual_shape=box, collision_shape=box, pose=Pose.from_xyz(20, 0, 0.1), sim_core=sim
    )
    out["class"] = type(robot).__name__
    SimObject.from_mesh(
        visual_shape=box, collision_shape=box, pose=Pose.from_xyz(21, 0, 0.1), sim_core=sim
    )
    robot.set_goal_pose(Pose.from_xyz(21, 0, 0.1))
    for _ in range(20):
        sim.step_once()
    out["events"] = bumps
with T.probe("create_shared_shapes") as out:
    visual_id, collision_id = SimObject.create_shared_shapes(
        visual_shape=ShapeParams(
            shape_type="mesh",
            mesh_path="visual.obj",
            mesh_scale=[1.0, 1.0, 1.0],
            rgba_color=[0.8, 0.2, 0.2, 1.0],
        ),
        collision_shape=ShapeParams(shape_type="box", half_extents=[0.5, 0.3, 0.2]),
        physics_client_id=sim_core.client,
    )
    out["ids_valid"] = [visual_id >= 0, collision_id >= 0]
with T.probe("from_mesh") as out:
    # Box visual + sphere collision
    obj = SimObject.from_mesh(
        visual_shape=ShapeParams(
            shape_type="box", half_extents=[0.5, 0.3, 0.2], rgba_color=[0.8, 0.2, 0.2, 1.0]
        ),
        collision_shape=ShapeParams(shape_type="sphere", radius=0.4),
        pose=Pose.from_xyz(0, 0, 1),
        mass=1.0,
        sim_core=sim_core,
    )
    out["mass"] = obj.mass
with T.probe("from_sdf") as out:
    shelves = SimObject.from_sdf("kiva_shelf/model.sdf", sim_core=sim)
    out["shelves"] = [[s.name, [round(v, 3) for v in s.get_pose().position]] for s in shelves]
with T.probe("from_params") as out:
    params = SimObjectSpawnParams(
        visual_shape=ShapeParams(
            shape_type="mesh",
            mesh_path="pallet.obj",
            mesh_scale=[0.5, 0.5, 0.5],
            rgba_color=[0.8, 0.6, 0.4, 1.0],
        ),
        collision_shape=ShapeParams(shape_type="box", half_extents=[0.5, 0.4, 0.1]),
        initial_pose=Pose.from_xyz(0, 0, 0.1),
        mass=1.0,
    )
    obj = SimObject.from_params(params, sim_core)
    out["pose"] = obj.get_pose().position
with T.probe("set_collision_mode") as out:
    # Change to static
    obj.set_collision_mode(CollisionMode.STATIC)
    a = obj.is_static
    # Disable collision
    obj.set_collision_mode(CollisionMode.DISABLED)
    # Enable 2D collision
    obj.set_collision_mode(CollisionMode.NORMAL_2D)
    out["modes"] = [a, obj.collision_mode]
with T.probe("attach_detach") as out:
    box = ShapeParams(shape_type="box", half_extents=[0.1, 0.1, 0.1])
    agent = Agent.from_urdf(
        "robots/mobile_robot.urdf", pose=Pose.from_xyz(30, 0, 0.05), sim_core=sim
    )
    pallet = SimObject.from_mesh(visual_shape=box, pose=Pose.from_xyz(31, 0, 0.1), sim_core=sim)
    box_obj = SimObject.from_mesh(visual_shape=box, pose=Pose.from_xyz(32, 0, 0.1), sim_core=sim)
    # Attach to base link at 0.5m in front
    out["attach"] = agent.attach_object(pallet, relative_pose=Pose.from_xyz(0.5, 0, 0))
    # Keep the child where it currently is in the world
    out["attach_keep"] = call_safely(
        agent.attach_object, box_obj, parent_link_index=2, keep_world_pose=True
    )
    out["box_pose_after_keep"] = [round(v, 3) for v in box_obj.get_pose().position]
    # Detach and leave in place
    out["detach"] = agent.detach_object(pallet)
    agent.attach_object(pallet, relative_pose=Pose.from_xyz(0.5, 0, 0))
    # Detach and place at absolute world position
    out["detach_drop_pose"] = agent.detach_object(pallet, drop_pose=Pose.from_xyz(10, 5, 0.1))
    agent.attach_object(pallet, relative_pose=Pose.from_xyz(0.5, 0, 0))
    # Detach and offset from current position (e.g. lower by 0.5m)
    out["detach_relative"] = agent.detach_object(
        pallet, drop_relative_pose=Pose.from_xyz(0, 0, -0.5)
    )
    out["pallet"] = [round(v, 3) for v in pallet.get_pose().position]
    # Attach to specific link by name
    out["attach_by_name"] = call_safely(
        agent.attach_object, pallet, parent_link_index="end_effector"
    )
    out["both"] = call_safely(
        agent.attach_object, pallet, relative_pose=Pose.from_xyz(0, 0, 0), keep_world_pose=True
    )
pybullet.disconnect(physicsClientId=sim.client)
T.dump()
