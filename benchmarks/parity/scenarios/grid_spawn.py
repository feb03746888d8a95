"""Grid spawning: names of grid-spawned agents, GridSpawnParams.from_dict / from_count, order."""

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.agent import AgentSpawnParams
from pybullet_fleet.agent_manager import AgentManager, GridSpawnParams
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.sim_object import ShapeParams

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])


def snapshot(objs):
    return [
        [o.name, round(o.get_pose().x, 3), round(o.get_pose().y, 3), round(o.get_pose().z, 3)]
        for o in objs
    ]


with T.probe("manager_grid") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    mgr = AgentManager(sim_core=sim)
    grid = GridSpawnParams(
        x_min=0, x_max=2, y_min=0, y_max=1, spacing=[2.0, 3.0, 0.0], offset=[1.0, 0.0, 0.1]
    )
    agents = mgr.spawn_agents_grid(
        5, grid, AgentSpawnParams(visual_shape=BOX, collision_shape=BOX, name="bot")
    )
    out["agents"] = snapshot(agents)
    out["total_cells"] = grid.total_cells
    out["unnamed"] = snapshot(
        mgr.spawn_agents_grid(
            2,
            GridSpawnParams(
                x_min=0, x_max=1, y_min=5, y_max=5, spacing=[1, 1, 0], offset=[0, 0, 0.1]
            ),
            AgentSpawnParams(visual_shape=BOX),
        )
    )
    out["count"] = mgr.get_object_count()
    pybullet.disconnect(physicsClientId=sim.client)
with T.probe("config_grid") as out:
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    objs = sim.spawn_robots_from_config(
        [
            {
                "name": "picker",
                "urdf_path": "robots/simple_cube.urdf",
                "motion_mode": "omnidirectional",
                "grid": {"count": 5, "spacing": [3.0, 3.0], "offset": [0, 0, 0.05], "columns": 2},
            },
            {
                "urdf_path": "robots/simple_cube.urdf",
                "grid": {"count": 2, "spacing": [1.0, 1.0], "offset": [0, 10, 0.05]},
            },
        ]
    )
    out["spawned"] = snapshot(objs)
    pybullet.disconnect(physicsClientId=sim.client)
with T.probe("grid_params") as out:
    g = GridSpawnParams.from_count(50, columns=10, spacing=[3.0, 3.0, 0.0])
    out["from_count"] = [
        g.x_min,
        g.x_max,
        g.y_min,
        g.y_max,
        g.z_min,
        g.z_max,
        list(g.spacing),
        list(g.offset),
    ]
    g2 = GridSpawnParams.from_count(7)
    out["from_count_default"] = [g2.x_max, g2.y_max, list(g2.spacing), list(g2.offset)]
    g3 = GridSpawnParams.from_dict(
        {"count": 50, "spacing": [3.0, 3.0], "offset": [0, 0, 0.05], "columns": 10}
    )
    out["from_dict_count"] = [g3.x_max, g3.y_max, list(g3.spacing), list(g3.offset)]
    g4 = GridSpawnParams.from_dict(
        {
            "x_min": 0,
            "x_max": 9,
            "y_min": 0,
            "y_max": 4,
            "spacing": [3.0, 3.0, 0.0],
            "offset": [0, 0, 0.05],
        }
    )
    out["from_dict_range"] = [g4.x_max, g4.y_max, g4.total_cells]
    out["too_many"] = call_safely(
        lambda: AgentManager().spawn_agent_grid_counts(
            GridSpawnParams(
                x_min=0, x_max=0, y_min=0, y_max=0, spacing=[1, 1, 0], offset=[0, 0, 0]
            ),
            [(AgentSpawnParams(), 2)],
        )
    )
T.dump()
