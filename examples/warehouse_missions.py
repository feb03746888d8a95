"""Warehouse missions: robots fetch totes from shelves to packing stations, written as async code.

Run:  python examples/warehouse_missions.py [--robots 6] [--orders 12] [--backend asyncio|trio]
                                            [--no-fields] [--max-steps N] [--gui]
 or:  fleet-async run examples/scenarios/warehouse.yaml   (the same shift, then a run summary)

The warehouse is the scenario file examples/scenarios/warehouse.yaml: shelf racks and packing
stations from a Gazebo world, a picker fleet from a grid entry, a patrol squad and a restocking
run of its own. Every robot has safety fields (the entities' ``safety_field`` key): something in
a robot's protective field stops it, something in its warning field slows it, as a real AGV's
scanner does. The scenario names this file's ``shift`` as its mission (its ``missions:``
section), so ``fleet-async run`` runs the same shift as this script.

``shift`` is a dispatcher. The pickers drive on one-way lanes (``lanes()``, a route graph the
viewer draws): east along the pick aisle in front of the totes, north through the cross aisles,
west along the station lane, south at the west wall. Each picker takes the order whose tote is
nearest ahead of it on the lanes, picks the tote from the aisle's edge, drives to a free slot
at its station, drops the tote there and comes back for more; a supervisor mission reports
progress every 20 s of sim time. The fields make robots wait for each other where lanes cross;
when robots hold each other for ``traffic.deadlock_after`` seconds (a ``deadlock_suspected``
event), the dispatcher's strategy is the simplest there is: the picker with the highest number
among them backs off a metre, waits a second and drives on. Each order is a task: its delivery
(or giving up on it) is a TASK_COMPLETED (TASK_FAILED) event, which the fleet KPIs count (the
run summary's 'tasks completed', a sweep's throughput). Everything happens in sim time: the
step loop advances only when every mission is waiting, so the run is deterministic and much
faster than real time. ``--no-fields`` runs the same shift without fields, for comparison.
"""

from __future__ import annotations

import argparse
import importlib.util
import itertools
import math
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
from fleet_async.core.routes import RouteGraph, RouteNode

SCENARIO = Path(__file__).resolve().parent / "scenarios" / "warehouse.yaml"
NORTHBOUND = (6.5, 12.5, 19.0)  # x of the northbound lanes in the cross aisles
SOUTHBOUND = (1.0, 7.5, 13.5)  # x of the southbound lanes (the cross aisles at x = 7, 13 have both)
PICK_LANE = 1.5  # y of the eastbound lane in the aisle in front of shelf row A
PICK_SIDING = 2.3  # y where a picker stands, off the lane, before it picks a tote
STATION_LANE = 14.6  # y of the westbound lane in front of the station tables
DROP_SIDING = 15.3  # y where a picker stands, off the lane, before it drops a tote
STATIONS = (5.0, 15.0)  # x of the station tables (at y = 17)
SLOTS = 6  # drop slots per station, side by side in front of its table
SLOT_SPACING = 0.6  # m between slots: a robot's field passes between the totes beside it
DROP_Y = 16.3  # y where totes are set down (the tables' front is at 16.6)
PICK_OFFSET = 0.7  # m from a tote where a picker stops: its protective field just misses it
BACK_OFF = 1.0  # m a picker reverses to break a suspected deadlock


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


def slot_x(station: int, slot: int) -> float:
    """x of drop slot ``slot`` of station ``station``."""
    return STATIONS[station] + SLOT_SPACING * (slot - (SLOTS - 1) / 2)


def lanes(homes: list[float], totes: list[float]) -> RouteGraph:
    """The pickers' one-way lanes: a loop through the aisles, with a stop in front of each
    tote (``pick@x``), each drop slot (``slot@x``) and each picker's dock (``dock@x``).

    Args:
        homes: x of the pickers' docks (south of the pick aisle; a dock is joined to the pick
            lane both ways: left at the start of the shift, reached at its end).
        totes: x of the totes (in front of shelf row A).
    """
    graph = RouteGraph(default_speed=1.5)

    def chain(name: str, points: list[tuple[float, float]]) -> None:
        """Nodes at ``points`` (already there: reused), joined in this order."""
        ids = []
        for x, y in points:
            node_id = f"{name}@{x:g},{y:g}"
            if node_id not in graph.nodes:
                graph.add_node(RouteNode(node_id, x, y))
            ids.append(node_id)
        for a, b in itertools.pairwise(ids):
            graph.add_edge(f"{a}>{b}", a, b)

    crossings = (PICK_LANE, 6.0, 10.0, STATION_LANE)  # the patrol's lanes are y = 6 and 10
    stops = sorted({*NORTHBOUND, *SOUTHBOUND, *homes, *totes})
    slots = [slot_x(s, k) for s in range(len(STATIONS)) for k in range(SLOTS)]
    chain("lane", [(x, PICK_LANE) for x in stops])
    chain("lane", [(x, STATION_LANE) for x in sorted({*NORTHBOUND, *SOUTHBOUND, *slots})[::-1]])
    for x in NORTHBOUND:
        chain("lane", [(x, y) for y in crossings])
    for x in SOUTHBOUND:
        chain("lane", [(x, y) for y in crossings[::-1]])
    for x in homes:
        chain("lane", [(x, -1.5), (x, PICK_LANE), (x, -1.5)])
    return graph


def node_at(graph: RouteGraph, x: float, y: float) -> str:
    """The id of the lane node at (x, y)."""
    return graph.nearest_node(x, y).node_id


def corners(graph: RouteGraph, start: str, goal: str) -> list[Pose]:
    """The route from ``start`` to ``goal`` as the poses where it turns (and its end): a
    picker drives each straight run in one go instead of stopping at every node."""
    points = [graph.node(start)] + [graph.node(e.end) for e in graph.shortest_path(start, goal)]
    out: list[Pose] = []
    for before, here, after in zip(points, points[1:], [*points[2:], None], strict=False):
        if after is not None:
            cross = (here.x - before.x) * (after.y - here.y) - (here.y - before.y) * (
                after.x - here.x
            )
            ahead = (here.x - before.x) * (after.x - here.x) + (here.y - before.y) * (
                after.y - here.y
            )
            if abs(cross) < 1e-9 and ahead > 0:  # straight on: no stop here
                continue
        out.append(Pose.from_xyz(here.x, here.y, 0.1))
    return out


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


async def run_shift(
    sim: MultiRobotSimulationCore, fleet: list[Agent], orders: list[Order]
) -> dict[str, int]:
    """The dispatcher: one mission per robot, plus a supervisor; returns the tally."""
    homes = [robot.get_pose().x for robot in fleet]
    graph = lanes(homes, [order.tote.get_pose().x for order in orders])
    sim.set_route_graph(graph)  # traced: the viewer draws the lanes
    backlog = list(orders)
    filled = [0] * len(STATIONS)
    tally = {"delivered": 0, "failed": 0, "backed_off": 0}
    nudges = {robot.object_id: sim.event() for robot in fleet}

    def say(message: str) -> None:
        print(f"[t={sim.sim_time:6.1f} s] {message}")

    def on_deadlock(agents: list[Agent], **_: object) -> None:
        # The strategy: of the pickers that hold each other, the highest-numbered backs off.
        ours = [a for a in agents if a.object_id in nudges]
        names = ", ".join(a.name or "?" for a in agents)
        if not ours:
            say(f"deadlock suspected: {names} (none of them is a picker)")
            return
        yielder = max(ours, key=lambda a: a.object_id)
        say(f"deadlock suspected: {names}; {yielder.name} backs off")
        nudges[yielder.object_id].set()

    async def leg(robot: Agent, goal: Pose) -> None:
        """Drive straight to ``goal``; back off and try again when told to (a deadlock)."""
        while True:
            nudge = nudges[robot.object_id] = sim.event()
            won, _ = await sim.race(robot.move([goal]), nudge)
            if won == 0:
                return
            tally["backed_off"] += 1
            here = robot.get_pose()
            yaw = here.yaw
            back = Pose.from_xyz(
                here.x - BACK_OFF * math.cos(yaw), here.y - BACK_OFF * math.sin(yaw), 0.1
            )
            with sim.move_on_after(5.0):  # something behind it too: give up backing off
                await robot.move([back], direction="backward")
            await sim.sleep(1.0)

    async def drive(robot: Agent, goal: str) -> None:
        here = robot.get_pose()
        start = graph.nearest_node(here.x, here.y)
        if math.hypot(start.x - here.x, start.y - here.y) > 0.05:  # at a siding: to the lane
            await leg(robot, Pose.from_xyz(start.x, start.y, 0.1))
        for pose in corners(graph, start.node_id, goal):
            await leg(robot, pose)

    def route_time(robot: Agent, order: Order) -> tuple[float, int]:
        here, tote = robot.get_pose(), order.tote.get_pose()
        path = graph.shortest_path(
            node_at(graph, here.x, here.y), node_at(graph, tote.x, PICK_LANE)
        )
        return (sum(graph.cost(edge) for edge in path), order.number)

    async def robot_mission(robot: Agent, home: float) -> None:
        while backlog:
            # Missions run one at a time between steps: no lock needed.
            order = min(backlog, key=lambda o: route_time(robot, o))
            backlog.remove(order)
            try:
                tote = order.tote.get_pose()
                await drive(robot, node_at(graph, tote.x, PICK_LANE))
                await robot.pick(
                    order.tote,
                    approach_offset=tote.y - PICK_SIDING,
                    pick_offset=PICK_OFFSET,
                    attach_relative_pose=Pose.from_xyz(0, 0, 0.25),
                )
                say(f"{robot.name} picked {order.tote.name} ({order})")
                slot = filled[order.station]
                filled[order.station] += 1
                x = slot_x(order.station, slot % SLOTS)
                await drive(robot, node_at(graph, x, STATION_LANE))
                await robot.drop(
                    Pose.from_xyz(x, DROP_Y, 0.08),
                    approach_offset=DROP_Y - DROP_SIDING,
                    drop_offset=PICK_OFFSET,
                )
                tally["delivered"] += 1
                # An order is a task: the fleet KPIs (sim.kpis(), fleet-async run / sweep)
                # count these events as tasks completed / failed.
                sim.events.emit(SimEvents.TASK_COMPLETED, sim=sim, agent=robot, task=order)
                say(f"{robot.name} delivered {order}")
            except ActionFailedError as exc:
                tally["failed"] += 1
                sim.events.emit(SimEvents.TASK_FAILED, sim=sim, agent=robot, task=order)
                say(f"{robot.name} gave up on {order}: {exc.action.error_message}")
        await drive(robot, node_at(graph, home, -1.5))
        say(f"{robot.name} is back at the dock")

    async def supervisor() -> None:
        while tally["delivered"] + tally["failed"] < len(orders):
            await sim.sleep(20.0)
            say(
                f"progress: {tally['delivered']}/{len(orders)} delivered, "
                f"{len(backlog)} not yet picked up"
            )

    sim.events.on(SimEvents.DEADLOCK_SUSPECTED, on_deadlock)
    try:
        async with sim.task_group() as tg:
            tg.start_soon(supervisor, name="supervisor")
            for robot, home in zip(fleet, homes, strict=True):
                tg.start_soon(robot_mission, robot, home, name=robot.name)
    finally:
        sim.events.off(SimEvents.DEADLOCK_SUSPECTED, on_deadlock)
    return tally


def waiting(sim: MultiRobotSimulationCore) -> str:
    """What the safety fields cost: stops, time stopped, deadlocks suspected."""
    stats = sim.safety.stats()
    stops = sum(s for s, _ in stats.values())
    stood = math.fsum(t for _, t in stats.values())
    return (
        f"{stops} safety stops, {stood:.1f} s stopped (summed over {len(stats)} robots with "
        f"fields), deadlocks suspected: {sim.safety.deadlocks_suspected}"
    )


async def shift(sim: MultiRobotSimulationCore, robots: int = 6, orders: int = 12) -> dict[str, int]:
    """The scenario's mission: dispatch ``robots`` pickers to ``orders`` orders, then report."""
    fleet, order_list = prepare(sim, robots, orders)
    tally = await run_shift(sim, fleet, order_list)
    print(
        f"shift over: {tally['delivered']}/{len(order_list)} orders delivered, "
        f"{tally['failed']} failed, {sim.sim_time:.1f} s of sim time, "
        f"{sim.collision_count} contacts began (collisions); {waiting(sim)}, "
        f"back-offs: {tally['backed_off']}"
    )
    return tally


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=6, choices=range(1, 7), metavar="1..6")
    parser.add_argument("--orders", type=int, default=12, choices=range(1, 13), metavar="1..12")
    parser.add_argument("--backend", choices=["asyncio", "trio"], default="asyncio")
    parser.add_argument("--max-steps", type=int, default=6000, help="stop after this many steps")
    parser.add_argument(
        "--no-fields", action="store_true", help="take the robots' safety fields away"
    )
    parser.add_argument(
        "--gui", action="store_true", help="open the PyBullet window (needs a display)"
    )
    args = parser.parse_args(argv)
    if args.backend == "trio" and importlib.util.find_spec("trio") is None:
        parser.error('--backend trio needs trio: pip install "fleet-async[trio]"')

    with build(args.gui) as sim:
        if args.no_fields:
            for agent in sim.agents:
                sim.safety.disable(agent)
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
