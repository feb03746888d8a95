"""Missions with devices, in exact sim time on both backends: awaiting a door and a lift,
robots contending for the doorway, the lift and a dispenser, and cancellation mid-motion."""

from __future__ import annotations

import logging
import math
import subprocess
import sys

import pytest

import fleet_async as fa
from fleet_async import (
    Agent,
    DeviceEvents,
    Door,
    DoorState,
    Elevator,
    ElevatorState,
    Pose,
    ShapeParams,
)
from fleet_async.core.devices import WorkcellPlugin

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def robot(sim, x: float, y: float, name: str, z: float = 0.1) -> Agent:
    return Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(x, y, z), sim_core=sim, name=name, controller="omni"
    )


def door(sim, **extra) -> Door:
    config = {"name": "door", "pose": [2.0, 0.0, 0.0], "yaw": math.pi / 2, "open_time": 1.0}
    made = Door.from_dict({**config, **extra}, sim)
    assert isinstance(made, Door)
    return made


def lift(sim) -> Elevator:
    made = Elevator.from_dict(
        {"name": "lift", "pose": [5.0, 0.0, 0.0], "floors": {"L1": 0.0, "L2": 3.0}, "speed": 1.5},
        sim,
    )
    assert isinstance(made, Elevator)
    return made


def record(sim, name: str) -> list[dict]:
    log: list[dict] = []
    sim.events.on(name, lambda **kw: log.append(kw))
    return log


async def test_awaiting_a_door_takes_exactly_its_open_and_close_times(fleet_sim):
    d = door(fleet_sim, close_time=0.5)
    done = await d.open()
    assert fleet_sim.step_count == 10 and d.is_open and done.end_time == pytest.approx(1.0)
    await d.close()
    assert fleet_sim.step_count == 15 and d.door_state is DoorState.CLOSED


async def test_a_mission_cancelled_while_a_door_opens_leaves_it_part_open(fleet_sim):
    d = door(fleet_sim)
    with fleet_sim.move_on_after(0.5) as scope:
        await d.open()
    assert scope.cancelled_caught and fleet_sim.step_count == 5
    await fleet_sim.sleep(1.0)
    assert d.openness == pytest.approx(0.5) and d.door_state is DoorState.CLOSED


async def test_two_robots_share_a_doorway_and_the_last_one_closes_it(fleet_sim):
    d = door(fleet_sim)
    states = record(fleet_sim, DeviceEvents.DOOR_STATE_CHANGED)
    first, second = robot(fleet_sim, 0.0, 0.3, "first"), robot(fleet_sim, 0.0, -0.3, "second")
    finished: dict[str, float] = {}
    seen: dict[str, list[float]] = {}

    async def cross(bot: Agent, y: float) -> None:
        await d.pass_through(bot, Pose.from_xyz(4.0, y, 0.1))
        finished[bot.name] = fleet_sim.now
        seen[bot.name] = second.get_pose().position.tolist()

    async with fleet_sim.task_group() as tg:
        tg.start_soon(cross, first, 0.3)
        tg.start_soon(cross, second, -0.3)
    assert finished["first"] < finished["second"]
    assert seen["first"] == [0.0, -0.3, 0.1]  # the second robot waited for the doorway
    closed = await fleet_sim.events.wait(
        DeviceEvents.DOOR_STATE_CHANGED, where=lambda state, **_: state is DoorState.CLOSED
    )
    assert closed["door"] is d
    assert fleet_sim.now == pytest.approx(finished["second"] + 1.0)  # closing, not awaited
    assert [s["state"] for s in states] == [
        DoorState.OPENING,
        DoorState.OPEN,  # opened once, after exactly open_time
        DoorState.CLOSING,
        DoorState.CLOSED,
    ]


async def test_awaiting_a_trip_takes_height_over_speed(fleet_sim):
    elevator = lift(fleet_sim)
    await elevator.go_to("L2")
    assert fleet_sim.step_count == 20  # 3 m at 1.5 m/s
    assert elevator.state is ElevatorState.ARRIVED and elevator.height == 3.0
    await fleet_sim.sleep(0.1)
    assert elevator.state is ElevatorState.IDLE


async def test_a_ride_first_calls_back_a_lift_stopped_between_floors(fleet_sim):
    elevator = lift(fleet_sim)
    with fleet_sim.move_on_after(1.0):
        await elevator.go_to("L2")  # a plain trip stops with the mission that awaited it
    await fleet_sim.sleep(0.5)
    assert elevator.height == pytest.approx(1.5) and elevator.state is ElevatorState.IDLE
    bot = robot(fleet_sim, 3.0, 0.0, "bot")
    departures = record(fleet_sim, DeviceEvents.ELEVATOR_DEPARTED)
    await elevator.ride(bot, "L2")
    assert [(d["target_floor"], d["passengers"]) for d in departures] == [
        ("L1", ()),
        ("L2", (bot,)),
    ]
    assert bot.get_pose().z == pytest.approx(3.1)


async def test_two_robots_ride_the_lift_one_after_the_other(fleet_sim):
    elevator = lift(fleet_sim)
    departures = record(fleet_sim, DeviceEvents.ELEVATOR_DEPARTED)
    first, second = robot(fleet_sim, 3.0, 0.5, "first"), robot(fleet_sim, 3.0, -0.5, "second")
    rode: dict[str, tuple[float, list[float]]] = {}

    async def go_up(bot: Agent) -> None:
        await elevator.ride(bot, "L2")
        rode[bot.name] = (fleet_sim.now, bot.get_pose().position.tolist())

    async with fleet_sim.task_group() as tg:
        tg.start_soon(go_up, first)
        tg.start_soon(go_up, second)
    assert [(d["target_floor"], d["passengers"]) for d in departures] == [
        ("L2", (first,)),
        ("L1", ()),  # called back down for the second robot
        ("L2", (second,)),
    ]
    assert rode["first"][0] < rode["second"][0]
    # both left the lift at the L2 landing, at their height above the floor
    assert rode["first"][1] == pytest.approx([3.45, 0.0, 3.1])
    assert rode["second"][1] == pytest.approx([3.45, 0.0, 3.1])
    assert fa.device_resource(elevator).count == 0


@pytest.mark.parametrize("fleet_backend", ["asyncio"])
async def test_cancelling_mid_ride_leaves_the_robot_on_the_lift_and_says_so(fleet_sim, caplog):
    elevator = lift(fleet_sim)
    bot = robot(fleet_sim, 3.0, 0.0, "bot")
    abandoned = record(fleet_sim, DeviceEvents.ELEVATOR_RIDE_ABANDONED)
    ride = fleet_sim.spawn(elevator.ride, bot, "L2", name="ride")
    await fleet_sim.events.wait(DeviceEvents.ELEVATOR_DEPARTED)
    departed = fleet_sim.now
    await fleet_sim.sleep(0.5)
    with caplog.at_level(logging.WARNING, logger="fleet_async.tasks.devices"):
        ride.cancel()
        await fleet_sim.sleep(0)
    assert not ride.is_alive
    assert abandoned == [{"elevator": elevator, "robot": bot, "floor": "L2"}]
    assert "bot stays on the platform" in caplog.text and "'L2'" in caplog.text
    assert elevator.state is ElevatorState.MOVING and fa.device_resource(elevator).count == 0
    await fleet_sim.events.wait(DeviceEvents.ELEVATOR_ARRIVED)
    assert fleet_sim.now == pytest.approx(departed + 2.0 - 0.1)  # departed in the step before
    assert bot.get_pose().position.tolist() == pytest.approx([5.0, 0.0, 3.1])
    assert not bot.is_attached()


async def test_robots_queue_at_a_dispenser_and_hand_items_to_an_ingestor(fleet_sim):
    plugin = fleet_sim.register_plugin(
        WorkcellPlugin,
        config={
            "processing_time": 0.5,
            "workcells": {
                "disp": {"kind": "dispenser", "position": [0.0, 0.0]},
                "ing": {"kind": "ingestor", "position": [0.0, 2.0], "processing_time": 0.3},
            },
        },
    )
    a, b = robot(fleet_sim, 0.3, 0.0, "a"), robot(fleet_sim, -0.3, 0.0, "b")
    done: dict[str, float] = {}

    async def fetch(bot: Agent) -> None:
        got = await plugin["disp"].dispense(bot)
        done[bot.name] = fleet_sim.now
        assert got.item.get_attached_parent() is bot

    async with fleet_sim.task_group() as tg:
        tg.start_soon(fetch, a)
        tg.start_soon(fetch, b)
    assert done == {"a": pytest.approx(0.5), "b": pytest.approx(1.0)}  # one at a time
    a.set_pose(Pose.from_xyz(0.0, 1.5, 0.1))
    start = fleet_sim.now
    taken = await plugin["ing"].ingest(a)
    assert fleet_sim.now == pytest.approx(start + 0.3)
    assert taken.item.sim_core is None and plugin["ing"].ingested == [taken.item]
    with pytest.raises(fa.ActionFailedError, match=r"b is 2.02 m from ing \(reach 1 m\)"):
        await plugin["ing"].ingest(b)


def test_the_mission_layer_registers_the_device_missions_when_it_is_loaded():
    # A fresh interpreter: this one has loaded the mission layer long ago.
    code = (
        "import fleet_async\n"
        "from fleet_async.core.missions import hooks\n"
        "try:\n"
        "    hooks.mission_hook('elevator.ride')\n"
        "except RuntimeError as e:\n"
        "    print('before:', e)\n"
        "import fleet_async.tasks\n"
        "print('after:', hooks.mission_hook('elevator.ride').__name__)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert "before: elevator.ride is a mission of the mission layer" in out
    assert "import fleet_async.tasks first" in out
    assert "after: ride" in out
