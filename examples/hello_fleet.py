"""Hello, fleet: four robots carry pallets from a shelf row to a packing station, headless.

Run:  python examples/hello_fleet.py [--max-steps N] [--gui]

Each robot gets an action sequence: pick its pallet, move to the station lane, drop the pallet
at the station, and wait a second there. The script prints every action as it completes, in
sim time, and a summary at the end.
"""

from __future__ import annotations

import argparse

from fleet_async import (
    Agent,
    DropAction,
    MoveAction,
    MultiRobotSimulationCore,
    Path,
    PickAction,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    SimulationParams,
    WaitAction,
)


def build(sim):
    """Spawn a shelf, four pallets and four differential robots; return robots and pallets."""
    # Place the shelf first, then make it static: a STATIC body never moves afterwards.
    shelf = SimObject.from_sdf("kiva_shelf/model.sdf", sim_core=sim)[0]
    shelf.set_pose(Pose.from_xyz(0.0, 6.0, 0.0))
    shelf.set_collision_mode("static")
    pallet_shape = ShapeParams("box", half_extents=[0.2, 0.2, 0.05], rgba_color=[0.8, 0.6, 0.3, 1])
    robot_shape = ShapeParams("box", half_extents=[0.3, 0.25, 0.1], rgba_color=[0.2, 0.4, 0.9, 1])
    robots, pallets = [], []
    for i in range(4):
        x = -3.0 + 2.0 * i
        pallets.append(
            SimObject.from_mesh(
                pallet_shape,
                pallet_shape,
                Pose.from_xyz(x, 4.0, 0.05),
                sim_core=sim,
                name=f"pallet{i}",
            )
        )
        robots.append(
            Agent.from_mesh(
                robot_shape,
                robot_shape,
                Pose.from_xyz(x, 0.0, 0.1),
                sim_core=sim,
                name=f"robot{i}",
                controller={"type": "differential", "max_linear_vel": 1.5, "max_linear_accel": 1.0},
            )
        )
    return robots, pallets


def mission(index, pallet):
    """Pick, drive to the station lane, drop at the station, rest."""
    station = Pose.from_xyz(-1.5 + index, -4.0, 0.05)
    return [
        PickAction(
            target_object_id=pallet.body_id,
            approach_offset=1.0,
            attach_relative_pose=Pose.from_xyz(0, 0, 0.2),
        ),
        MoveAction(
            path=Path.from_positions([[-3.0 + 2.0 * index, -1.0, 0.1], [-1.5 + index, -2.0, 0.1]])
        ),
        DropAction(drop_pose=station, approach_offset=0.5),
        WaitAction(duration=1.0),
    ]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-steps", type=int, default=3000, help="stop after this many steps")
    parser.add_argument(
        "--gui", action="store_true", help="open the PyBullet window (needs a display)"
    )
    args = parser.parse_args(argv)

    params = SimulationParams(
        gui=args.gui, target_rtf=1.0 if args.gui else 0.0, monitor=False, timestep=0.1
    )
    with MultiRobotSimulationCore(params) as sim:
        robots, pallets = build(sim)
        done = {"completed": 0, "failed": 0}

        def report(outcome):
            def handler(agent, action):
                done[outcome] += 1
                detail = f": {action.error_message}" if action.error_message else ""
                print(
                    f"[t={action.end_time:6.1f} s] {agent.name} {outcome} "
                    f"{type(action).__name__}{detail}"
                )

            return handler

        sim.events.on(SimEvents.ACTION_COMPLETED, report("completed"))
        sim.events.on(SimEvents.ACTION_FAILED, report("failed"))
        for i, (robot, pallet) in enumerate(zip(robots, pallets, strict=True)):
            robot.add_action_sequence(mission(i, pallet))

        while sim.step_count < args.max_steps and not all(
            r.is_action_queue_empty() for r in robots
        ):
            sim.step_once()

        delivered = sum(not p.is_attached() and p.get_pose().y < -3.0 for p in pallets)
        print(
            f"{delivered}/{len(pallets)} pallets delivered, {done['completed']} actions completed, "
            f"{done['failed']} failed, in {sim.sim_time:.1f} s of sim time ({sim.step_count} steps)"
        )
    return 0 if delivered == len(pallets) and done["failed"] == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
