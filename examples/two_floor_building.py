"""Two-floor building: couriers fetch items on the ground floor and deliver them upstairs.

Run:  python examples/two_floor_building.py [--deliveries 1] [--backend asyncio|trio]
                                            [--max-steps N] [--record out.gif]
                                            [--trace out.fatrace]

With --trace, `fleet-async view out.fatrace` replays the run in the browser: set the z range
to 2-5 m to see the upper floor.

The building is the scenario file examples/scenarios/two_floor_world.yaml: a dispenser on
the ground floor, a lift, and upstairs a wall with a sliding door in front of an ingestor.
Four couriers share them. Two are driven by a behaviour tree (examples/trees/deliver.xml,
BehaviorTree.CPP v4 XML), two by missions written as async code; both do the same round:
dispense an item, ride the lift up, pass the door, hand the item to the ingestor, pass the
door again, ride down, go home. The lift and the doorway are shared under the sim-aware
Resource rules (one courier at a time, first come first served), the dispenser and the
ingestor serve one courier at a time, and everything happens in sim time.
"""

from __future__ import annotations

import argparse
import importlib.util
from pathlib import Path
from typing import TypeVar

import fleet_async as fa
from fleet_async import (
    Agent,
    DeviceEvents,
    Door,
    Elevator,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    Workcell,
    load_yaml_config,
)
from fleet_async.behavior import BehaviorTreeFactory

T = TypeVar("T")

HERE = Path(__file__).resolve().parent
SCENARIO = HERE / "scenarios" / "two_floor_world.yaml"
TREE = HERE / "trees" / "deliver.xml"
LANES = (-1.5, -0.5, 0.5, 1.5)  # each courier's y lane
SLOTS = ((0.75, 0.0), (0.0, 0.75), (-0.75, 0.0), (0.0, -0.75))  # around the dispenser
DOWN, UP = 0.1, 3.1  # a courier's base height on each floor


def spots(k: int) -> dict[str, object]:
    """Courier ``k``'s own places (its blackboard, for the tree couriers)."""
    lane = LANES[k]
    return {
        "home": Pose.from_xyz(-3.0, lane, DOWN),
        "dispenser_slot": Pose.from_xyz(*SLOTS[k], DOWN),
        "upstairs_lane": Pose.from_xyz(7.6, lane, UP),
        "through_door": [
            Pose.from_xyz(9.3, 0, UP),
            Pose.from_xyz(10.7, 0, UP),
            Pose.from_xyz(11.5, lane, UP),
        ],
        "ingestor_slot": Pose.from_xyz(12.3, 0.4 * lane, UP),
        "back_through_door": [
            Pose.from_xyz(10.7, 0, UP),
            Pose.from_xyz(9.3, 0, UP),
            Pose.from_xyz(8.8, lane, UP),
        ],
        "downstairs_lane": Pose.from_xyz(4.4, lane, DOWN),
    }


def build(backend_gui: bool) -> tuple[MultiRobotSimulationCore, list[Agent]]:
    """The building from its scenario file, plus four couriers (two blue, two orange)."""
    config = load_yaml_config(SCENARIO)
    config["simulation"].update(gui=backend_gui)
    sim = MultiRobotSimulationCore.from_dict(config, source=str(SCENARIO), base_dir=SCENARIO.parent)
    couriers = []
    for k, name in enumerate(("tree0", "tree1", "mission0", "mission1")):
        color = [0.2, 0.45, 0.9, 1.0] if name.startswith("tree") else [0.95, 0.45, 0.15, 1.0]
        body = ShapeParams("box", half_extents=[0.25, 0.2, 0.1], rgba_color=color)
        home = spots(k)["home"]
        assert isinstance(home, Pose)
        couriers.append(
            Agent.from_mesh(body, body, home, sim_core=sim, name=name, controller="omni")
        )
    return sim, couriers


def device(sim: MultiRobotSimulationCore, name: str, kind: type[T]) -> T:
    """The scenario's ``kind`` object called ``name``."""
    found = next(obj for obj in sim.sim_objects if obj.name == name)
    if not isinstance(found, kind):
        raise TypeError(f"{name!r} is a {type(found).__name__}, not a {kind.__name__}")
    return found


async def deliver(sim: MultiRobotSimulationCore, robot: Agent, k: int, rounds: int) -> None:
    """The mission couriers' round, in Python (the same as examples/trees/deliver.xml)."""
    places = spots(k)
    dispenser, ingestor = device(sim, "dispenser", Workcell), device(sim, "ingestor", Workcell)
    lift, door = device(sim, "lift", Elevator), device(sim, "office_door", Door)
    for _ in range(rounds):
        await robot.move(places["dispenser_slot"])
        await dispenser.dispense(robot)
        await lift.ride(robot, "L2", exit_pose=places["upstairs_lane"])
        await door.pass_through(robot, places["through_door"])
        await robot.move(places["ingestor_slot"])
        await ingestor.ingest(robot)
        await door.pass_through(robot, places["back_through_door"])
        await lift.ride(robot, "L1", exit_pose=places["downstairs_lane"])
        await robot.move(places["home"])


async def shift(sim: MultiRobotSimulationCore, couriers: list[Agent], rounds: int) -> float:
    """Run every courier's round at once; return the sim time the last one got home."""
    factory = BehaviorTreeFactory()
    async with sim.task_group() as tg:
        for k, robot in enumerate(couriers):
            if robot.name.startswith("tree"):
                tree = factory.create_tree_from_file(
                    TREE, agent=robot, blackboard={**spots(k), "deliveries": rounds}
                )
                tg.start_soon(tree.run, name=robot.name)
            else:
                tg.start_soon(deliver, sim, robot, k, rounds, name=robot.name)
    return sim.now


def narrate(sim: MultiRobotSimulationCore) -> dict[str, int]:
    """Print what the devices do; return counts."""
    counts = {"dispensed": 0, "ingested": 0, "trips": 0, "door_openings": 0}

    def say(text: str) -> None:
        print(f"[t={sim.sim_time:6.1f} s] {text}")

    def dispensed(workcell, robot, item, **_):
        counts["dispensed"] += 1
        say(f"{robot.name} got {item.name} from the {workcell.name}")

    def ingested(workcell, robot, item, **_):
        counts["ingested"] += 1
        say(f"{robot.name} delivered {item.name} to the {workcell.name}")

    def departed(elevator, floor, target_floor, passengers, **_):
        counts["trips"] += 1
        riders = ", ".join(p.name for p in passengers) or "empty"
        say(f"{elevator.name}: {floor} -> {target_floor} ({riders})")

    def door_changed(door, state, **_):
        if state.value == "opening":
            counts["door_openings"] += 1
        say(f"{door.name} {state.value}")

    sim.events.on(DeviceEvents.WORKCELL_DISPENSED, dispensed)
    sim.events.on(DeviceEvents.WORKCELL_INGESTED, ingested)
    sim.events.on(DeviceEvents.ELEVATOR_DEPARTED, departed)
    sim.events.on(DeviceEvents.DOOR_STATE_CHANGED, door_changed)
    return counts


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--deliveries", type=int, default=1, help="rounds per courier")
    parser.add_argument("--backend", choices=["asyncio", "trio"], default="asyncio")
    parser.add_argument("--max-steps", type=int, default=4000, help="stop after this many steps")
    parser.add_argument("--record", metavar="OUT.gif", help="record the run to a GIF")
    parser.add_argument(
        "--trace", metavar="OUT.fatrace", help="trace the run for the browser viewer"
    )
    parser.add_argument("--gui", action="store_true", help="open the PyBullet window")
    args = parser.parse_args(argv)
    if args.backend == "trio" and importlib.util.find_spec("trio") is None:
        parser.error('--backend trio needs trio: pip install "fleet-async[trio]"')

    sim, couriers = build(args.gui)
    with sim:
        counts = narrate(sim)
        if args.trace:
            sim.start_trace(args.trace)
        if args.record:
            sim.start_recording(
                args.record,
                width=640,
                height=400,
                fps=4,
                camera_mode="manual",
                camera_params={
                    "distance": 13.0,
                    "yaw": -20.0,
                    "pitch": -50.0,
                    "target": [7.0, 0.0, 1.5],
                },
            )
        finished = fa.run(
            sim,
            shift,
            sim,
            couriers,
            args.deliveries,
            backend=args.backend,
            until=args.max_steps * sim.params.timestep,
        )
        if args.record:
            print(f"recorded {sim.stop_recording()}")
        if args.trace:
            sim.stop_trace()
            print(f"traced to {args.trace}: fleet-async view {args.trace}")
        expected = len(couriers) * args.deliveries
        if finished is None:
            print(
                f"stopped at the step limit ({args.max_steps} steps): "
                f"{counts['ingested']}/{expected} delivered"
            )
            return 1
        print(
            f"shift over at t={finished:.1f} s: {counts['ingested']}/{expected} items delivered, "
            f"{counts['trips']} lift trips, the door opened {counts['door_openings']} times"
        )
    return 0 if counts["ingested"] == expected else 1


if __name__ == "__main__":
    raise SystemExit(main())
