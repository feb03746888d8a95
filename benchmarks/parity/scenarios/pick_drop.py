"""PickAction / DropAction with approach_offset and pick_offset: where the robot stops, times."""

import math

import pybullet
from parity_trace import Trace, angle
from pybullet_fleet.action import DropAction, MoveAction, PickAction
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams, SimObject

T = Trace()
ROBOT = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])
CRATE = ShapeParams(shape_type="box", half_extents=[0.1, 0.1, 0.1])


def phase_of(action):
    # Not in the seed: the incumbent keeps it in `_phase`; read whichever exists.
    value = getattr(action, "phase", None) or getattr(action, "_phase", None)
    return getattr(value, "value", value)


def scene(mode="omnidirectional"):
    sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
    agent = Agent.from_mesh(
        visual_shape=ROBOT,
        collision_shape=ROBOT,
        pose=Pose.from_xyz(0, 0, 0.1),
        sim_core=sim,
        motion_mode=mode,
    )
    crate = SimObject.from_mesh(
        visual_shape=CRATE,
        collision_shape=CRATE,
        pose=Pose.from_xyz(5, 0, 0.1),
        mass=0.0,
        pickable=True,
        sim_core=sim,
        name="crate",
    )
    return sim, agent, crate


def run(name, make_actions, mode="omnidirectional", max_steps=600):
    with T.probe(name) as out:
        sim, agent, crate = scene(mode)
        actions = make_actions(crate)
        agent.add_action_sequence(actions)
        sim.initialize_simulation()
        stops, phases, last, seen = [], [], None, {}
        for step in range(1, max_steps + 1):
            sim.step_once()
            pos = [round(v, 3) for v in agent.get_pose().position[:2]]
            if pos == last and (not stops or stops[-1]["at"] != pos):
                stops.append(
                    {
                        "at": pos,
                        "step": step,
                        "dist_to_crate_start": round(math.dist(pos, [5, 0]), 3),
                    }
                )
            last = pos
            for i, a in enumerate(actions):
                ph = phase_of(a)
                if ph is not None and seen.get(i) != ph:
                    seen[i] = ph
                    phases.append({"action": i, "phase": ph, "step": step, "at": pos})
            if agent.is_action_queue_empty():
                out["queue_empty_step"] = step
                break
        cp = crate.get_pose()
        out.update(
            stops=stops,
            phases=phases,
            actions=[
                {
                    "type": type(a).__name__,
                    "status": a.status,
                    "start": a.start_time,
                    "end": a.end_time,
                    "error": a.error_message,
                }
                for a in actions
            ],
            crate=[cp.x, cp.y, cp.z, angle(cp.yaw)],
            crate_attached=crate.is_attached(),
            attached_ids=[o.object_id for o in agent.get_attached_objects()],
            agent=[agent.get_pose().x, agent.get_pose().y, angle(agent.get_pose().yaw)],
        )
        pybullet.disconnect(physicsClientId=sim.client)


run("pick_default", lambda c: [PickAction(target_object_id=c.body_id)])
run("pick_approach1.5", lambda c: [PickAction(target_object_id=c.body_id, approach_offset=1.5)])
run(
    "pick_approach1_pick0.3",
    lambda c: [PickAction(target_object_id=c.body_id, approach_offset=1.0, pick_offset=0.3)],
)
run(
    "pick_no_approach",
    lambda c: [PickAction(target_object_id=c.body_id, use_approach=False, pick_offset=0.3)],
)
run("pick_by_position", lambda c: [PickAction(target_position=[5, 0, 0.1], search_radius=0.5)])
run("pick_by_position_miss", lambda c: [PickAction(target_position=[8, 0, 0.1], search_radius=0.5)])
run(
    "pick_diff",
    lambda c: [PickAction(target_object_id=c.body_id, approach_offset=1.0, pick_offset=0.3)],
    mode="differential",
)
run(
    "pick_then_drop",
    lambda c: [
        PickAction(
            target_object_id=c.body_id,
            approach_offset=1.0,
            pick_offset=0.3,
            attach_relative_pose=Pose.from_xyz(0.3, 0, 0.2),
        ),
        DropAction(drop_pose=Pose(position=[5, 5, 0.1]), approach_offset=1.0),
    ],
)
run(
    "pick_move_drop_offset",
    lambda c: [
        PickAction(target_object_id=c.body_id),
        MoveAction(path=Path.from_positions([[5, 3, 0.1]])),
        DropAction(
            drop_pose=Pose(position=[5, 5, 0.1]),
            approach_offset=1.0,
            drop_offset=0.4,
            place_gently=False,
            drop_height=0.1,
        ),
    ],
)
with T.probe("defaults") as out:
    p, d = PickAction(target_object_id=1), DropAction(drop_pose=Pose(position=[1, 2, 0]))
    out.update(
        pick_approach=p.approach_offset,
        drop_approach=d.approach_offset,
        pick_offset=p.pick_offset,
        drop_offset=d.drop_offset,
        search=p.search_radius,
        skip=p.move_skip_threshold,
        rel=p.attach_relative_pose.position,
        drop_orientation=d.drop_pose.orientation,
    )
T.dump()
