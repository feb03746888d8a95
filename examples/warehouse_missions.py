"""Warehouse missions: robots fetch totes from shelves to packing stations, written as async code.

Run:  python examples/warehouse_missions.py [--robots 6] [--orders 12] [--backend asyncio|trio]
                                            [--max-steps N] [--gui]
 or:  fleet-async run examples/scenarios/warehouse.yaml   (the same shift, then a run summary)

The warehouse is the scenario file examples/scenarios/warehouse.yaml: shelf racks and packing
stations from a Gazebo world, a picker fleet from a grid entry, a patrol squad and a restocking
run of its own. The scenario names this file's ``shift`` as its mission (its ``missions:``
section), so ``fleet-async run`` runs the same shift as this script. ``shift`` is a dispatcher:
it starts one mission per picker. Each picker takes the next order from the shared order list,
picks the tote at the shelf, drives to its station through a cross aisle, drops the tote there
and comes back for more; a supervisor mission reports progress every 20 s of sim time. Each
order is a task: its delivery (or giving up on it) is a TASK_COMPLETED (TASK_FAILED) event,
which the fleet KPIs count (the run summary's 'tasks completed', a sweep's throughput).
Everything happens in sim time: the step loop advances only when every mission is waiting, so
the run is deterministic and much faster than real time.
"""

from __future__ import annotations

import argparse
import importlib.util
from dataclasses import dataclass
from pathlib import Path

import fleet_async as fa
from fleet_async import (
    ActionFailedError,
    Agent,
    MultiRobotSimulationCore,
    Pose,
    SimEvents,
    SimObject,
    load_yaml_config,
)

SCENARIO = Path(__file__).resolve().parent / "scenarios" / "warehouse.yaml"
CROSS_AISLES = (1.0, 7.0, 13.0, 19.0)  # x of the free lanes between shelf racks
PICK_LANE = 2.0  # y of the aisle in front of shelf row A
STATION_LANE = 15.0  # y of the lane in front of the station tables
STATIONS = (5.0, 15.0)  # x of the station tables (at y = 17)


@dataclass
class Order:
    """Bring ``tote`` to station ``station`` (an index into STATIONS), the body ``station_body``."""

    number: int
    tote: SimObject
    station: int
    station_body: SimObject

    def __str__(self) -> str:
        # What the log, the KPIs' task events and the viewer's timeline call this order.
        return f"order {self.number}: {self.tote.name} to {self.station_body.name}"


def build(gui: bool) -> MultiRobotSimulationCore:
    """Load the warehouse scenario (headless and unpaced unless ``gui``)."""
    config = load_yaml_config(SCENARIO)
    config["simulation"].update(gui=gui, target_rtf=1.0 if gui else 0.0)
    return MultiRobotSimulationCore.from_dict(
        config, source=str(SCENARIO), base_dir=SCENARIO.parent
    )


def prepare(
    sim: MultiRobotSimulationCore, robots: int, orders: int
) -> tuple[list[Agent], list[Order]]:
    """The first ``robots`` pickers, and an order list for the first ``orders`` totes.

    Bodies keep the names the scenario gives them (picker_0, tote_A1_0, station_1, ...), so
    the log below, the run summary, the trace and the viewer all say the same thing.
    """
    fleet = sim.get_manager("pickers").objects[:robots]
    totes = [o for o in sim.sim_objects if (o.name or "").startswith("tote_")][:orders]
    tables = [o for o in sim.sim_objects if (o.name or "").startswith("station_")]
    bodies = [min(tables, key=lambda o, x=x: abs(o.get_pose().x - x)) for x in STATIONS]
    return fleet, [
        Order(k, tote, k % len(STATIONS), bodies[k % len(STATIONS)]) for k, tote in enumerate(totes)
    ]


def station_pose(station: int, slot: int) -> Pose:
    """Where a tote goes at a station: side by side on the floor in front of the table."""
    return Pose.from_xyz(STATIONS[station] - 0.6 + 0.4 * (slot % 4), 16.2 - 0.4 * (slot // 4), 0.08)


def via_cross_aisle(robot: Agent, y_to: float, x_to: float | None = None) -> list[Pose]:
    """A path to lane ``y_to`` through the nearest cross aisle (never through a rack)."""
    here = robot.get_pose()
    xc = min(CROSS_AISLES, key=lambda x: abs(x - here.x))
    path = [Pose.from_xyz(xc, here.y, 0.1), Pose.from_xyz(xc, y_to, 0.1)]
    if x_to is not None:
        path.append(Pose.from_xyz(x_to, y_to, 0.1))
    return path


async def run_shift(
    sim: MultiRobotSimulationCore, fleet: list[Agent], orders: list[Order]
) -> dict[str, int]:
    """The dispatcher: one mission per robot, plus a supervisor; returns the tally."""
    backlog = list(orders)
    filled = [0] * len(STATIONS)
    tally = {"delivered": 0, "failed": 0}

    def say(message: str) -> None:
        print(f"[t={sim.sim_time:6.1f} s] {message}")

    async def robot_mission(robot: Agent) -> None:
        home = robot.get_pose()
        while backlog:
            order = backlog.pop(0)  # missions run one at a time between steps: no lock needed
            try:
                if robot.get_pose().y > PICK_LANE + 1.0:  # at the stations: back to the racks
                    await robot.move(via_cross_aisle(robot, PICK_LANE))
                await robot.pick(
                    order.tote,
                    approach_offset=1.0,
                    pick_offset=0.4,
                    attach_relative_pose=Pose.from_xyz(0, 0, 0.2),
                )
                say(f"{robot.name} picked {order.tote.name} ({order})")
                await robot.move(via_cross_aisle(robot, STATION_LANE, STATIONS[order.station]))
                slot = filled[order.station]
                filled[order.station] += 1
                await robot.drop(station_pose(order.station, slot), approach_offset=0.8)
                tally["delivered"] += 1
                # An order is a task: the fleet KPIs (sim.kpis(), fleet-async run / sweep)
                # count these events as tasks completed / failed.
                sim.events.emit(SimEvents.TASK_COMPLETED, sim=sim, agent=robot, task=order)
                say(f"{robot.name} delivered {order}")
            except ActionFailedError as exc:
                tally["failed"] += 1
                sim.events.emit(SimEvents.TASK_FAILED, sim=sim, agent=robot, task=order)
                say(f"{robot.name} gave up on {order}: {exc.action.error_message}")
        await robot.move([*via_cross_aisle(robot, PICK_LANE), home])
        say(f"{robot.name} is back at the dock")

    async def supervisor() -> None:
        while tally["delivered"] + tally["failed"] < len(orders):
            await sim.sleep(20.0)
            say(
                f"progress: {tally['delivered']}/{len(orders)} delivered, "
                f"{len(backlog)} not yet picked up"
            )

    async with sim.task_group() as tg:
        tg.start_soon(supervisor, name="supervisor")
        for robot in fleet:
            tg.start_soon(robot_mission, robot, name=robot.name)
    return tally


async def shift(sim: MultiRobotSimulationCore, robots: int = 6, orders: int = 12) -> dict[str, int]:
    """The scenario's mission: dispatch ``robots`` pickers to ``orders`` orders, then report."""
    fleet, order_list = prepare(sim, robots, orders)
    tally = await run_shift(sim, fleet, order_list)
    print(
        f"shift over: {tally['delivered']}/{len(order_list)} orders delivered, "
        f"{tally['failed']} failed, {sim.sim_time:.1f} s of sim time, "
        f"{sim.collision_count} contacts began (collisions)"
    )
    return tally


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=6, choices=range(1, 7), metavar="1..6")
    parser.add_argument("--orders", type=int, default=12, choices=range(1, 13), metavar="1..12")
    parser.add_argument("--backend", choices=["asyncio", "trio"], default="asyncio")
    parser.add_argument("--max-steps", type=int, default=6000, help="stop after this many steps")
    parser.add_argument(
        "--gui", action="store_true", help="open the PyBullet window (needs a display)"
    )
    args = parser.parse_args(argv)
    if args.backend == "trio" and importlib.util.find_spec("trio") is None:
        parser.error('--backend trio needs trio: pip install "fleet-async[trio]"')

    with build(args.gui) as sim:
        tally = fa.run(
            sim,
            shift,
            sim,
            args.robots,
            args.orders,
            backend=args.backend,
            until=args.max_steps * sim.params.timestep,
        )
        if tally is None:
            print(f"stopped at the step limit ({args.max_steps} steps) before the shift ended")
            return 1
    return 0 if tally["delivered"] == args.orders else 1


if __name__ == "__main__":
    raise SystemExit(main())
