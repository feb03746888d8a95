"""Warehouse missions: robots fetch totes from shelves to packing stations, written as async code.

Run:  python examples/warehouse_missions.py [--robots 6] [--orders 12] [--backend asyncio|trio]
                                            [--max-steps N] [--gui]

A dispatcher coroutine starts one mission per robot. Each robot takes the next order from the
shared order list, picks the tote at the shelf, drives to the station lane, drops the tote at
its station and comes back for more; a supervisor mission reports progress every 20 s of sim
time. Everything happens in sim time: the step loop advances only when every mission is
waiting, so the run is deterministic and much faster than real time.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import fleet_async as fa
from fleet_async import (
    ActionFailedError,
    Agent,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimObject,
    SimulationParams,
)

TOTE = ShapeParams("box", half_extents=[0.15, 0.15, 0.08], rgba_color=[0.9, 0.5, 0.1, 1])
ROBOT = ShapeParams("box", half_extents=[0.3, 0.25, 0.1], rgba_color=[0.2, 0.4, 0.9, 1])


@dataclass
class Order:
    """Bring ``tote`` to station ``station``."""

    number: int
    tote: SimObject
    station: int


def build(
    sim: MultiRobotSimulationCore, robots: int, orders: int
) -> tuple[list[Agent], list[Order]]:
    """Shelves along y = 8, totes in front of them, robots at the dock, stations at y = -6."""
    for i in range(3):
        shelf = SimObject.from_sdf(
            "kiva_shelf/model.sdf", sim_core=sim, collision_mode="static", name_prefix=f"shelf{i}"
        )[0]
        shelf.set_pose(Pose.from_xyz(-6.0 + 6.0 * i, 9.5, 0.0))
    totes = [
        SimObject.from_mesh(
            TOTE,
            TOTE,
            Pose.from_xyz(-8.0 + 16.0 * k / max(orders - 1, 1), 8.0, 0.08),
            sim_core=sim,
            name=f"tote{k}",
        )
        for k in range(orders)
    ]
    fleet = [
        Agent.from_mesh(
            ROBOT,
            ROBOT,
            Pose.from_xyz(-5.0 + 2.0 * i, 0.0, 0.1),
            sim_core=sim,
            name=f"robot{i}",
            controller={"type": "differential", "max_linear_vel": 1.5, "max_linear_accel": 1.0},
        )
        for i in range(robots)
    ]
    return fleet, [Order(k, tote, k % 4) for k, tote in enumerate(totes)]


def station_pose(station: int, slot: int) -> Pose:
    """Where a tote goes at a station (slots stack side by side)."""
    return Pose.from_xyz(-4.5 + 3.0 * station + 0.4 * (slot % 3), -6.0 - 0.4 * (slot // 3), 0.08)


async def run_shift(
    sim: MultiRobotSimulationCore, fleet: list[Agent], orders: list[Order]
) -> dict[str, int]:
    """The dispatcher: one mission per robot, plus a supervisor; returns the tally."""
    backlog = list(orders)
    filled = [0, 0, 0, 0]
    tally = {"delivered": 0, "failed": 0}

    def say(message: str) -> None:
        print(f"[t={sim.sim_time:6.1f} s] {message}")

    async def robot_mission(robot: Agent) -> None:
        home = robot.get_pose()
        while backlog:
            order = backlog.pop(0)  # missions run one at a time between steps: no lock needed
            try:
                await robot.pick(
                    order.tote, approach_offset=1.0, attach_relative_pose=Pose.from_xyz(0, 0, 0.2)
                )
                say(f"{robot.name} picked {order.tote.name} (order {order.number})")
                await robot.move(Pose.from_xyz(-4.5 + 3.0 * order.station, -3.0, 0.1))
                slot = filled[order.station]
                filled[order.station] += 1
                await robot.drop(station_pose(order.station, slot), approach_offset=0.8)
                tally["delivered"] += 1
                say(f"{robot.name} delivered order {order.number} to station {order.station}")
            except ActionFailedError as exc:
                tally["failed"] += 1
                say(f"{robot.name} gave up on order {order.number}: {exc.action.error_message}")
        await robot.move(home)
        say(f"{robot.name} is back at the dock")

    async def supervisor() -> None:
        while tally["delivered"] + tally["failed"] < len(orders):
            await sim.sleep(20.0)
            say(f"progress: {tally['delivered']}/{len(orders)} delivered, {len(backlog)} waiting")

    async with sim.task_group() as tg:
        tg.start_soon(supervisor, name="supervisor")
        for robot in fleet:
            tg.start_soon(robot_mission, robot, name=robot.name)
    return tally


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=6)
    parser.add_argument("--orders", type=int, default=12)
    parser.add_argument("--backend", choices=["asyncio", "trio"], default="asyncio")
    parser.add_argument("--max-steps", type=int, default=6000, help="stop after this many steps")
    parser.add_argument(
        "--gui", action="store_true", help="open the PyBullet window (needs a display)"
    )
    args = parser.parse_args(argv)

    params = SimulationParams(
        gui=args.gui, target_rtf=1.0 if args.gui else 0.0, monitor=False, timestep=0.1
    )
    with MultiRobotSimulationCore(params) as sim:
        fleet, orders = build(sim, args.robots, args.orders)
        tally = fa.run(
            sim,
            run_shift,
            sim,
            fleet,
            orders,
            backend=args.backend,
            until=args.max_steps * params.timestep,
        )
        if tally is None:
            print(f"stopped at the step limit ({args.max_steps} steps) before the shift ended")
            return 1
        print(
            f"shift over: {tally['delivered']}/{len(orders)} orders delivered, "
            f"{tally['failed']} failed, {sim.sim_time:.1f} s of sim time, "
            f"{sim.collision_count} collisions"
        )
    return 0 if tally["delivered"] == len(orders) else 1


if __name__ == "__main__":
    raise SystemExit(main())
