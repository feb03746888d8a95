"""Collision events between two robots: when they start / end, payloads, active pairs, margin."""

import pybullet
from parity_trace import Trace
from pybullet_fleet.action import MoveAction
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.events import SimEvents
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.25, 0.25, 0.1])


def head_on(name, gap_goal=0.0, freq=None, max_steps=60, **params):
    with T.probe(name) as out:
        sim = MultiRobotSimulationCore(
            SimulationParams(gui=False, monitor=False, target_rtf=0, **params)
        )
        if freq is not None:
            sim.set_collision_check_frequency(freq)
        a = Agent.from_mesh(
            visual_shape=BOX,
            collision_shape=BOX,
            pose=Pose.from_xyz(0, 0, 0.1),
            sim_core=sim,
            motion_mode="omnidirectional",
            name="a",
        )
        Agent.from_mesh(
            visual_shape=BOX,
            collision_shape=BOX,
            pose=Pose.from_xyz(3, 0, 0.1),
            sim_core=sim,
            motion_mode="omnidirectional",
            name="b",
        )
        log = []
        sim.events.on(
            SimEvents.COLLISION_STARTED,
            lambda **kw: log.append(
                {
                    "ev": "start",
                    "t": sim.sim_time,
                    "step": sim.step_count,
                    "keys": sorted(kw),
                    "names": sorted([kw["obj_a"].name, kw["obj_b"].name]),
                }
            ),
        )
        sim.events.on(
            SimEvents.COLLISION_ENDED,
            lambda **kw: log.append(
                {"ev": "end", "t": sim.sim_time, "step": sim.step_count, "keys": sorted(kw)}
            ),
        )
        a.events.on(
            SimEvents.COLLISION_STARTED,
            lambda **kw: log.append(
                {"ev": "a.start", "keys": sorted(kw), "other": kw["other"].name}
            ),
        )
        # a drives through b's spot and back out the other side; b waits.
        a.add_action(MoveAction(path=Path.from_positions([[6, 0, 0.1]])))
        sim.initialize_simulation()
        pairs_log, prev = [], None
        for step in range(1, max_steps + 1):
            sim.step_once()
            pairs = [sorted(p) for p in sim.get_active_collision_pairs()]
            if pairs != prev:
                pairs_log.append({"step": step, "x": round(a.get_pose().x, 3), "pairs": len(pairs)})
                prev = pairs
        out.update(
            events=log,
            pair_changes=pairs_log,
            collision_count=sim.collision_count,
            id_order=[p[0] < p[1] for p in sim.get_active_collision_pairs()],
        )
        pybullet.disconnect(physicsClientId=sim.client)


def gap(name, distance, nudge=True, **params):
    with T.probe(name) as out:
        sim = MultiRobotSimulationCore(
            SimulationParams(gui=False, monitor=False, target_rtf=0, **params)
        )
        SimObject.from_mesh(
            visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0, 0, 0.1), sim_core=sim
        )
        b = SimObject.from_mesh(
            visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(3, 0, 0.1), sim_core=sim
        )
        sim.initialize_simulation()
        target = Pose.from_xyz(0.5 + distance, 0, 0.1)
        if nudge:  # b moves into place: the incumbent only checks objects that moved
            sim.step_once()
            b.set_pose(target)
        else:
            b.set_pose(target)
            sim.initialize_simulation()
        sim.step_once()
        pairs, _ = sim.check_collisions()
        out.update(active=len(sim.get_active_collision_pairs()), check=len(pairs))


head_on("head_on_every_step")
head_on("head_on_2hz", freq=2.0)
head_on("head_on_param_freq_5", collision_check_frequency=5.0)
gap("gap_0.01_default_margin", 0.01)
gap("gap_0.03_default_margin", 0.03)
gap("gap_0.01_margin0", 0.01, collision_margin=0.0)
gap("touching", 0.0)
gap("overlap_0.05", -0.05)
gap("overlap_0.05_placed_before_start", -0.05, nudge=False)
with T.probe("strict_handler_signature") as out:
    # A handler written to the documented kwargs only (no **kwargs).
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    SimObject.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0, 0, 0.1), sim_core=sim
    )
    SimObject.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0.3, 0, 0.1), sim_core=sim
    )
    seen = []
    sim.events.on(SimEvents.COLLISION_STARTED, lambda obj_a, obj_b: seen.append(1))
    sim.events.on(SimEvents.PRE_STEP, lambda dt, sim_time: seen.append(("pre", sim_time)))
    sim.initialize_simulation()
    sim.step_once()
    out["calls"] = seen
T.dump()
