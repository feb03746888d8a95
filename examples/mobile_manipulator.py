"""A mobile manipulator fetches two boxes from a shelf table and delivers them to a station.

Run:  python examples/mobile_manipulator.py [--max-steps N] [--gui]

The project's mobile_manipulator (a differential base with a lifting rail and a 4-joint arm)
drives up to the pick table, stopping ``pick_offset`` short of the box, reaches for it with IK
(wheels are locked out of the solve automatically), attaches it to its end effector and
reverses out, the arm still where the reach left it; then it drives to the station table and
places the box the same way. The script is written as an async mission: ``await robot.pick(...)`` queues a PickAction
and resumes, in sim time, when it ends.
"""

from __future__ import annotations

import argparse

import fleet_async as fa
from fleet_async import (
    Agent,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimObject,
    SimulationParams,
)

TABLE = ShapeParams("box", half_extents=[0.08, 0.3, 0.2], rgba_color=[0.55, 0.4, 0.25, 1])
BOX = ShapeParams("box", half_extents=[0.03, 0.03, 0.03], rgba_color=[0.9, 0.2, 0.2, 1])
TABLE_TOP = 0.4
PICK_TABLE = (4.0, 0.0)
STATION = (0.0, 4.0)


def build(sim):
    """Spawn the robot, the two tables and two boxes on the pick table."""
    robot = Agent.from_urdf(
        "mobile_manipulator",
        pose=Pose([0.0, 0.0, 0.15]),
        sim_core=sim,
        name="fetcher",
        controller={"type": "differential", "max_linear_vel": 1.0, "max_linear_accel": 1.0},
    )
    for x, y in (PICK_TABLE, STATION):
        SimObject.from_mesh(
            TABLE,
            TABLE,
            Pose([x, y, TABLE_TOP / 2]),
            sim_core=sim,
            pickable=False,
            collision_mode="static",
        )
    boxes = [
        SimObject.from_mesh(
            BOX,
            BOX,
            Pose([PICK_TABLE[0], PICK_TABLE[1] + dy, TABLE_TOP + 0.03]),
            sim_core=sim,
            name=f"box{i}",
        )
        for i, dy in enumerate((-0.12, 0.12))
    ]
    return robot, boxes


async def fetch(sim, robot, boxes, log):
    """Carry each box from the pick table to the station, one at a time."""
    for i, box in enumerate(boxes):
        x, y, z = box.get_pose().position
        action = await robot.pick(
            box,
            pick_offset=0.32,
            ee_target_position=[x, y, z + 0.04],
            attach_link="end_effector",
            attach_relative_pose=Pose([0.0, 0.0, -0.04]),
            continue_on_ik_failure=False,
        )
        log(f"picked {box.name} (took {action.get_duration():.1f} s)")
        spot = [STATION[0] - 0.12 + 0.24 * i, STATION[1], TABLE_TOP + 0.03]
        action = await robot.drop(
            Pose(spot),
            drop_offset=0.32,
            ee_target_position=[spot[0], spot[1], spot[2] + 0.04],
            continue_on_ik_failure=False,
        )
        log(f"placed {box.name} at the station (took {action.get_duration():.1f} s)")


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
        robot, boxes = build(sim)

        def log(message):
            print(f"[t={sim.sim_time:5.1f} s] {message}")

        async def main_mission():
            await fetch(sim, robot, boxes, log)

        fa.run(sim, main_mission, until=args.max_steps * params.timestep)
        delivered = sum(
            not b.is_attached() and abs(b.get_pose().position[1] - STATION[1]) < 1e-6 for b in boxes
        )
        print(
            f"{delivered}/{len(boxes)} boxes delivered in {sim.sim_time:.1f} s of sim time "
            f"({sim.step_count} steps)"
        )
    return 0 if delivered == len(boxes) else 1


if __name__ == "__main__":
    raise SystemExit(main())
