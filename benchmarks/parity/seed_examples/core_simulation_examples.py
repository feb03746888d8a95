"""Seed examples of pybullet_fleet.core_simulation (YAML layouts, callbacks, managers, collisions,
profiling, recording, batch spawn, reset). Paths the seed uses as placeholders
('/path/to/office.world', 'my_ros_pkg.entities.ForkliftAgent') are left out (see probe names)."""

import os

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.agent import Agent, AgentSpawnParams
from pybullet_fleet.agent_manager import AgentManager, GridSpawnParams
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject
from pybullet_fleet.types import SpatialHashCellSizeMode

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.3, 0.3, 0.1])


def close(sim):
    if pybullet.isConnected(physicsClientId=sim.client):
        pybullet.disconnect(physicsClientId=sim.client)


with open("nested.yaml", "w") as fh:  # the seed's nested layout, minus its placeholder world file
    fh.write("""simulation:
  gui: false
  physics: false
entities:
  - name: robot0
    urdf_path: "robots/mobile_robot.urdf"
    pose: [0, 0, 0.05]
  - type: sim_object
    name: box0
    visual_shape:
      shape_type: box
      half_extents: [0.3, 0.3, 0.1]
    pose: [3, 0, 0.1]
""")
with T.probe("from_yaml_nested_without_world") as out:
    sim = MultiRobotSimulationCore.from_yaml("nested.yaml")
    out["objects"] = [
        [o.name, type(o).__name__, [round(v, 3) for v in o.get_pose().position]]
        for o in sim.sim_objects
    ]
    close(sim)
with open("flat.yaml", "w") as fh:
    fh.write("gui: false\nphysics: false\ntimestep: 0.1\n")
with T.probe("from_yaml_flat") as out:
    sim = MultiRobotSimulationCore.from_yaml("flat.yaml")
    out["timestep"] = sim.params.timestep
    close(sim)
with T.probe("from_dict_nested") as out:
    sim = MultiRobotSimulationCore.from_dict(
        {
            "simulation": {"gui": False, "timestep": 0.05},
            "entities": [
                {"name": "r", "urdf_path": "robots/simple_cube.urdf", "pose": [1, 0, 0.05]}
            ],
        }
    )
    out["timestep"] = sim.params.timestep
    out["names"] = [o.name for o in sim.sim_objects]
    close(sim)
sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
with T.probe("register_callback") as out:
    n = []

    def my_callback(sim_core, dt):
        for obj in sim_core.sim_objects:
            if isinstance(obj, Agent):
                # Update agent logic
                pass
        n.append(sim_core.step_count)

    sim.register_callback(my_callback, frequency=10.0)  # 10 Hz
    for _ in range(5):
        sim.step_once()
    out["calls"] = n
with T.probe("register_manager") as out:
    grid_params = GridSpawnParams(
        x_min=0, x_max=4, y_min=0, y_max=1, spacing=[2, 2, 0], offset=[0, 10, 0.1]
    )
    spawn_params = AgentSpawnParams(visual_shape=BOX, collision_shape=BOX)
    mgr = AgentManager()
    sim.register_manager(mgr)
    mgr.spawn_agents_grid(10, grid_params, spawn_params)
    # When sim.remove_object(agent) is called later,
    # mgr.objects is kept in sync automatically.
    sim.remove_object(mgr.objects[0])
    out["manager_count"] = len(mgr.objects)
    out["sim_count"] = len(sim.sim_objects)
with T.probe("set_collision_check_frequency") as out:
    sim.set_collision_check_frequency(None)  # Every step
    sim.set_collision_check_frequency(1.0)  # 1 Hz (once per second)
    sim.set_collision_check_frequency(10.0)  # 10 Hz
    sim.set_collision_check_frequency(0)  # Disable
    out["ok"] = True
    sim.set_collision_check_frequency(None)
with T.probe("batch_spawn") as out:
    params_list = [
        AgentSpawnParams(visual_shape=BOX, initial_pose=Pose.from_xyz(i, 30, 0.1)) for i in range(5)
    ]
    with sim.batch_spawn():
        for params in params_list:
            Agent.from_params(params, sim)
    # rendering restored to previous state, spatial grid rebuilt once
    out["count"] = len(sim.sim_objects)
with T.probe("set_collision_spatial_hash_cell_size_mode") as out:
    # Recalculate with current mode
    out["recalc"] = sim.set_collision_spatial_hash_cell_size_mode()
    # Switch to constant mode with specific size
    out["constant"] = sim.set_collision_spatial_hash_cell_size_mode(
        mode=SpatialHashCellSizeMode.CONSTANT, cell_size=3.0
    )
    # Switch to auto_adaptive mode
    out["adaptive"] = sim.set_collision_spatial_hash_cell_size_mode(
        mode=SpatialHashCellSizeMode.AUTO_ADAPTIVE
    )
with T.probe("add_object") as out:
    shape = pybullet.createCollisionShape(
        pybullet.GEOM_BOX, halfExtents=[0.1] * 3, physicsClientId=sim.client
    )
    body_id = pybullet.createMultiBody(
        0, shape, basePosition=[0, -5, 0.1], physicsClientId=sim.client
    )
    # Manual addition (not recommended - SimObject does this automatically)
    obj = SimObject(body_id=body_id, sim_core=None)
    sim_core = sim
    sim_core.add_object(obj)
    out["manual_id"] = obj.object_id
    body_id2 = pybullet.createMultiBody(
        0, shape, basePosition=[1, -5, 0.1], physicsClientId=sim.client
    )
    # Automatic addition (recommended)
    obj2 = SimObject(body_id=body_id2, sim_core=sim_core)  # Calls add_object() internally
    out["auto_id"] = obj2.object_id
    out["in_sim"] = [obj in sim.sim_objects, obj2 in sim.sim_objects]
with T.probe("remove_object_(seed_uses_sim_core.spawn_robot)") as out:
    obj = call_safely(lambda: sim_core.spawn_robot())
    out["spawn_robot"] = obj
with T.probe("collisions") as out:
    a = SimObject.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(50, 0, 0.1), sim_core=sim
    )
    b = SimObject.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(55, 0, 0.1), sim_core=sim
    )
    sim.step_once()
    b.set_pose(Pose.from_xyz(50.4, 0, 0.1))
    sim.step_once()
    # Without profiling
    pairs, _ = sim.filter_aabb_pairs()
    # With profiling
    pairs, timings = sim.filter_aabb_pairs(return_profiling=True)
    out["filter_total"] = call_safely(lambda: timings["total"] >= 0)
    out["filter_timing_keys"] = sorted(timings) if timings else timings
    # Without profiling
    active_pairs, _ = sim.check_collisions()
    # With profiling
    active_pairs, timings = sim.check_collisions(return_profiling=True)
    out["check_total"] = call_safely(lambda: timings["total"] >= 0)
    out["check_timing_keys"] = sorted(timings) if timings else timings
    out["active"] = len(active_pairs)
    lines = []
    # Check if any collisions are active
    if sim_core.get_active_collision_pairs():
        lines.append("Collisions detected!")
    # Get detailed collision info
    for obj_id_i, obj_id_j in sim_core.get_active_collision_pairs():
        obj_i = sim_core._sim_objects_dict[obj_id_i]  # noqa: SLF001  # the seed's code
        obj_j = sim_core._sim_objects_dict[obj_id_j]  # noqa: SLF001  # the seed's code
        lines.append(f"Collision: {type(obj_i).__name__} <-> {type(obj_j).__name__}")
    out["printed"] = lines
with T.probe("record_profiling") as out:
    import time

    def cb(sim_core, dt):
        t0 = time.perf_counter()
        sim_core.record_profiling("custom_logic", (time.perf_counter() - t0) * 1000)

    sim.register_callback(cb)
    prof = sim.step_once(return_profiling=True)
    out["has_custom"] = "custom_logic" in prof
with T.probe("get_memory_usage") as out:
    mem = sim.get_memory_usage()
    if mem:
        print(f"Python heap: {mem['current_mb']:.2f} MB, Peak: {mem['peak_mb']:.2f} MB")
    out["mem_disabled"] = mem
with T.probe("initialize_simulation_custom_loop") as out:
    sim.initialize_simulation()
    steps = 0
    while steps < 5:
        sim.step_once()
        steps += 1
    out["after"] = [sim.step_count, round(sim.sim_time, 6)]
with T.probe("reset") as out:
    sim.reset()  # All objects removed, PyBullet world cleared
    params = AgentSpawnParams(visual_shape=BOX, initial_pose=Pose.from_xyz(0, 0, 0.1))
    agent = Agent.from_params(params, sim)
    sim.step_once()
    out["objects"] = len(sim.sim_objects)
with T.probe("spawn_robots_from_config_(seed_list_minus_forklift)") as out:
    spawned = sim.spawn_robots_from_config(
        [
            # Individual robot
            {"urdf_path": "robots/mobile_robot.urdf", "pose": [0, 0, 0.05]},
            # Grid with batch controller (shorthand)
            {
                "urdf_path": "robots/mobile_robot.urdf",
                "motion_mode": "omnidirectional",
                "batch_controller": "batch_omni",
                "grid": {"count": 20, "spacing": [3, 3]},
            },
            # Grid assigned to a named manager
            {
                "urdf_path": "robots/mobile_robot.urdf",
                "manager": "delivery_fleet",
                "grid": {"count": 50, "spacing": [2, 2]},
            },
        ]
    )
    out["count"] = len(spawned)
    out["fleet"] = call_safely(lambda: len(sim.get_manager("delivery_fleet").objects))
with T.probe("spawn_robots_from_config_custom_type_unregistered") as out:
    out["forklift"] = call_safely(
        lambda: len(
            sim.spawn_robots_from_config(
                [{"type": "forklift", "urdf_path": "robots/forklift.urdf", "pose": [10, 0, 0]}]
            )
        )
    )
with T.probe("start_recording") as out:
    rec = call_safely(lambda: type(sim.start_recording("output.gif", duration=0.5)).__name__)
    out["recorder"] = rec
    if not isinstance(rec, dict):
        sim.run_simulation(duration=1.0)  # File is auto-saved when run_simulation ends
    out["gif_written"] = os.path.exists("output.gif")
close(sim)
with T.probe("get_manager_from_yaml") as out:
    with open("config.yaml", "w") as fh:
        fh.write(
            "simulation:\n  gui: false\nmanagers:\n  - name: delivery_fleet\n"
            "entities:\n  - urdf_path: robots/simple_cube.urdf\n    manager: delivery_fleet\n"
            "    grid: {count: 3, spacing: [2, 2]}\n"
        )
    sim = MultiRobotSimulationCore.from_yaml("config.yaml")
    fleet = sim.get_manager("delivery_fleet")
    for agent in fleet.objects:
        agent.set_path([Pose.from_xyz(5, 5, 0.05)])
    out["fleet"] = len(fleet.objects)
    close(sim)
T.dump()
