"""Doors, elevators and workcells without missions: timing in exact steps, states, events,
request policies, passengers, collisions, scenarios and errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fleet_async import (
    Agent,
    DeviceEvents,
    Door,
    DoorParams,
    DoorState,
    Elevator,
    ElevatorParams,
    ElevatorRequestPolicy,
    ElevatorRequestResult,
    ElevatorState,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    Workcell,
    WorldLoadError,
)
from fleet_async.core.devices import WorkcellPlugin

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def robot(sim, x: float, y: float, z: float = 0.1, name: str = "r") -> Agent:
    return Agent.from_mesh(BOX, BOX, Pose.from_xyz(x, y, z), sim_core=sim, name=name)


def record(sim, *names: str) -> list[tuple[int, str, dict]]:
    """(step index during which it was emitted, event, payload) for each device event."""
    log: list[tuple[int, str, dict]] = []
    for name in names:
        sim.events.on(name, lambda _n=name, **kw: log.append((sim.step_count, _n, kw)))
    return log


def steps(sim, n: int) -> None:
    for _ in range(n):
        sim.step_once()


def lift(sim, policy: str = "reject", **extra) -> Elevator:
    config = {
        "name": "lift",
        "pose": [5.0, 0.0, 0.0],
        "floors": {"L1": 0.0, "L2": 3.0, "L3": 6.0},
        "speed": 1.5,
        "request_policy": policy,
        **extra,
    }
    device = Elevator.from_dict(config, sim)
    assert isinstance(device, Elevator)
    return device


# ----- doors ------------------------------------------------------------------------------------


def test_a_door_opens_in_exactly_its_open_time(sim):
    door = Door.from_dict({"name": "d", "pose": [2.0, 0.0, 0.0], "open_time": 1.0}, sim)
    log = record(sim, DeviceEvents.DOOR_STATE_CHANGED)
    door.request_open()
    steps(sim, 9)
    assert door.door_state is DoorState.OPENING
    assert door.openness == pytest.approx(0.9)
    steps(sim, 1)  # the 10th step ends at 1.0 s
    assert door.door_state is DoorState.OPEN and door.openness == 1.0
    assert door.get_pose().position.tolist() == pytest.approx([3.0, 0.0, 0.0])  # slid a width
    assert [(k, e["state"], e["previous"]) for k, _, e in log] == [
        (0, DoorState.OPENING, DoorState.CLOSED),
        (9, DoorState.OPEN, DoorState.OPENING),
    ]
    assert all(e["door"] is door for _, _, e in log)


def test_a_hinged_door_swings_about_its_hinge(sim):
    door = Door.from_dict(
        {"pose": [0.0, 0.0, 0.0], "door_type": "hinged", "width": 1.0, "open_time": 0.5}, sim
    )
    door.request_open()
    steps(sim, 5)
    pose = door.get_pose()
    assert door.is_open
    assert pose.position.tolist() == pytest.approx([-0.5, 0.5, 0.0])  # centre swung round -x
    assert pose.yaw == pytest.approx(math.pi / 2)


def test_request_close_reverses_an_opening_door_from_where_it_is(sim):
    door = Door.from_dict({"pose": [0.0, 0.0, 0.0], "open_time": 2.0, "close_time": 1.0}, sim)
    door.request_open()
    steps(sim, 6)
    assert door.openness == pytest.approx(0.3)
    door.request_close()  # 0.3 of the close time left: 3 steps
    steps(sim, 2)
    assert door.door_state is DoorState.CLOSING
    steps(sim, 1)
    assert door.door_state is DoorState.CLOSED and door.openness == 0.0
    assert door.get_pose().position.tolist() == pytest.approx([0.0, 0.0, 0.0])


def test_a_door_stopped_part_way_is_closed_and_holds(sim):
    door = Door.from_dict({"pose": [0.0, 0.0, 0.0], "open_time": 1.0}, sim)
    door.request_open()
    steps(sim, 4)
    door.clear_actions()
    steps(sim, 3)
    assert door.door_state is DoorState.CLOSED
    assert door.openness == pytest.approx(0.4)


def test_a_closed_door_is_an_obstacle_and_an_open_one_is_not(sim):
    # The leaf spans the doorway across y; a robot drives through it along x.
    door = Door.from_dict({"pose": [2.0, 0.0, 0.0], "yaw": math.pi / 2, "open_time": 0.5}, sim)
    hits = []
    sim.events.on(
        SimEvents.COLLISION_STARTED,
        lambda obj_a, obj_b, **_: hits.append({obj_a.name, obj_b.name}),
    )
    bot = robot(sim, 0.0, 0.0, name="bot")
    bot.set_pose(Pose.from_xyz(2.0, 0.0, 0.1))  # in the doorway, door closed
    steps(sim, 1)
    assert hits == [{"bot", None}]
    bot.set_pose(Pose.from_xyz(0.0, 0.0, 0.1))
    door.request_open()
    steps(sim, 6)
    assert door.is_open
    bot.set_pose(Pose.from_xyz(2.0, 0.0, 0.1))
    steps(sim, 1)
    assert len(hits) == 1
    assert door.get_pose().position.tolist() == pytest.approx([2.0, 1.0, 0.0])


def test_door_params_are_checked():
    with pytest.raises(ValueError, match=r"DoorParams.open_time: .* got -1"):
        DoorParams.from_dict({"open_time": -1})
    with pytest.raises(ValueError, match=r"DoorParams.door_type: 'revolving'"):
        DoorParams.from_dict({"door_type": "revolving"})
    with pytest.raises(ValueError, match="unknown key 'open_positions'"):
        DoorParams.from_dict({"open_positions": {"hinge": 1.57}})


# ----- elevators --------------------------------------------------------------------------------


def test_a_trip_carries_the_robot_and_its_load_in_exactly_height_over_speed(sim):
    elevator = lift(sim)
    assert elevator.height == 0.0 and elevator.state is ElevatorState.IDLE
    bot = robot(sim, 5.2, 0.1, name="bot")
    tote = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(5.2, 0.1, 0.4), sim_core=sim, name="tote")
    bot.attach_object(tote, keep_world_pose=True)
    outside = robot(sim, 7.0, 0.0, name="outside")
    log = record(sim, DeviceEvents.ELEVATOR_DEPARTED, DeviceEvents.ELEVATOR_ARRIVED)
    assert elevator.request_floor("L2") is ElevatorRequestResult.ACCEPTED
    steps(sim, 1)
    assert elevator.state is ElevatorState.MOVING and elevator.passengers == [bot]
    steps(sim, 18)
    assert elevator.height == pytest.approx(2.85)
    assert bot.get_pose().z == pytest.approx(2.95) and tote.get_pose().z == pytest.approx(3.25)
    steps(sim, 1)  # 3 m at 1.5 m/s: 20 steps
    assert elevator.state is ElevatorState.ARRIVED and elevator.current_floor == "L2"
    assert bot.get_pose().z == pytest.approx(3.1) and not bot.is_attached()
    assert tote.get_attached_parent() is bot and outside.get_pose().z == pytest.approx(0.1)
    steps(sim, 1)
    assert elevator.state is ElevatorState.IDLE
    assert [(k, e) for k, e, _ in log] == [
        (0, DeviceEvents.ELEVATOR_DEPARTED),
        (19, DeviceEvents.ELEVATOR_ARRIVED),
    ]
    assert log[0][2]["passengers"] == (bot,) and log[1][2]["passengers"] == (bot,)


@pytest.mark.parametrize(
    ("policy", "results", "pending", "visits"),
    [
        ("reject", ["rejected", "rejected"], (), ["L2"]),
        ("queue", ["queued", "queued"], ("L3", "L1"), ["L2", "L3", "L1"]),
        ("replace_next", ["queued", "replaced"], ("L1",), ["L2", "L1"]),
    ],
)
def test_request_policies_while_the_lift_is_busy(sim, policy, results, pending, visits):
    elevator = lift(sim, policy)
    arrivals = record(sim, DeviceEvents.ELEVATOR_ARRIVED)
    assert elevator.request_floor("L2") is ElevatorRequestResult.ACCEPTED
    assert elevator.request_floor("L2") is ElevatorRequestResult.REJECTED  # already heading there
    steps(sim, 3)
    got = [elevator.request_floor("L3").value, elevator.request_floor("L1").value]
    assert got == results
    assert elevator.pending_floors == pending
    assert elevator.request_policy is ElevatorRequestPolicy(policy)
    steps(sim, 120)
    assert [e["floor"] for _, _, e in arrivals] == visits


def test_requests_for_the_current_or_an_unknown_floor(sim):
    elevator = lift(sim)
    assert elevator.request_floor("L1") is ElevatorRequestResult.REJECTED
    with pytest.raises(ValueError, match=r"lift.request_floor: unknown floor 'L9'; floors: \['L1'"):
        elevator.request_floor("L9")


def test_a_cancelled_trip_stops_between_floors_and_releases_its_passengers(sim):
    elevator = lift(sim)
    bot = robot(sim, 5.0, 0.0, name="bot")
    elevator.request_floor("L3")
    steps(sim, 10)
    elevator.clear_actions()
    steps(sim, 2)
    assert elevator.state is ElevatorState.IDLE
    assert elevator.height == pytest.approx(1.5) and elevator.current_floor == "L1"
    assert not bot.is_attached() and bot.get_pose().z == pytest.approx(1.6)


def test_passengers_are_found_in_the_platforms_own_frame(sim):
    elevator = lift(sim, yaw=math.pi / 2, platform_size=[1.0, 3.0])
    aboard = robot(sim, 6.2, 0.0, name="aboard")  # 1.2 m along the platform's long side
    beside = robot(sim, 5.0, 0.8, name="beside")  # 0.8 m across its short side: off it
    high = robot(sim, 5.0, 0.0, z=2.7, name="high")  # above the cabin height
    assert elevator.objects_on_platform() == [aboard]
    assert not beside.is_attached() and not high.is_attached()


def test_elevator_geometry_helpers(sim):
    elevator = lift(sim, initial_floor="L2", landings={"L3": [1.6, 0.0]})
    assert elevator.height == 3.0 and elevator.current_floor == "L2"
    assert elevator.floor_at(3.1) == "L2" and elevator.floor_at(-1.0) == "L1"
    assert elevator.landing_pose("L1", 0.1).position.tolist() == pytest.approx([3.45, 0.0, 0.1])
    assert elevator.landing_pose("L3").position.tolist() == pytest.approx([6.6, 0.0, 6.0])


def test_elevator_params_are_checked():
    params = ElevatorParams
    with pytest.raises(ValueError, match=r"ElevatorParams.floors: expected a mapping"):
        params.from_dict({})
    with pytest.raises(ValueError, match=r"ElevatorParams.initial_floor: 'L7' is not a floor"):
        params.from_dict({"floors": {"L1": 0.0}, "initial_floor": "L7"})
    with pytest.raises(ValueError, match=r"ElevatorParams.speed: expected a finite number > 0"):
        params.from_dict({"floors": {"L1": 0.0}, "speed": 0})


# ----- workcells --------------------------------------------------------------------------------


def stations(sim, **extra) -> WorkcellPlugin:
    plugin = sim.register_plugin(
        WorkcellPlugin,
        config={
            "processing_time": 0.5,
            "workcells": {
                "disp": {"kind": "dispenser", "position": [0.0, 0.0]},
                "ing": {"kind": "ingestor", "position": [4.0, 0.0], "processing_time": 0.3},
            },
            **extra,
        },
    )
    assert isinstance(plugin, WorkcellPlugin)
    return plugin


def test_a_dispenser_hands_over_an_item_after_its_processing_time(sim):
    plugin = stations(sim)
    bot = robot(sim, 0.3, 0.0, name="bot")
    action = plugin.dispense("disp", bot)
    steps(sim, 4)
    assert action.item is None and not bot.get_attached_objects()
    steps(sim, 1)
    assert action.end_time == pytest.approx(0.5)
    item = action.item
    assert item is not None and item.name == "disp_item0"
    assert item.get_attached_parent() is bot
    assert item.get_pose().position.tolist() == pytest.approx([0.3, 0.0, 0.3])
    assert plugin["disp"].dispensed == [item]


def test_an_ingestor_takes_the_item_at_once_and_consumes_it(sim):
    plugin = stations(sim)
    bot = robot(sim, 0.0, 0.0, name="bot")
    dispensed = plugin.dispense("disp", bot)
    steps(sim, 5)
    bot.set_pose(Pose.from_xyz(4.5, 0.0, 0.1))
    log = record(sim, DeviceEvents.WORKCELL_INGESTED)
    ingest = plugin.ingest("ing", bot)
    steps(sim, 1)
    item = dispensed.item
    assert not bot.get_attached_objects() and item.get_pose().position.tolist() == [4.0, 0.0, 0.1]
    steps(sim, 2)
    assert ingest.end_time == pytest.approx(0.8) and item.sim_core is None
    assert [(e["workcell"].name, e["robot"], e["item"]) for _, _, e in log] == [("ing", bot, item)]


def test_station_errors_name_the_robot_and_the_reach(sim):
    plugin = stations(sim, reach=0.5)
    bot = robot(sim, 2.0, 0.0, name="bot")
    action = plugin.dispense("disp", bot)
    steps(sim, 1)
    assert action.error_message == "bot is 2.00 m from disp (reach 0.5 m)"
    bot.set_pose(Pose.from_xyz(4.0, 0.0, 0.1))
    empty = plugin.ingest("ing", bot)
    steps(sim, 1)
    assert empty.error_message == "bot carries nothing to ingest"
    with pytest.raises(ValueError, match="ing is an ingestor; it cannot dispense"):
        plugin["ing"].request_dispense(bot)
    with pytest.raises(KeyError, match=r"no workcell 'nope'; workcells: \['disp', 'ing'\]"):
        plugin.workcell("nope")


def test_workcell_config_errors_name_the_key(sim):
    with pytest.raises(ValueError, match=r"workcell.workcells.d: unknown key\(s\) \['procesing'\]"):
        sim.register_plugin(WorkcellPlugin, config={"workcells": {"d": {"procesing": 1}}})


# ----- scenarios --------------------------------------------------------------------------------


SCENARIO = """
simulation: {gui: false, monitor: false, target_rtf: 0, timestep: 0.1}
entities:
  - {type: door, name: door_1, pose: [3, 0, 0], yaw: 1.5708, open_time: 1.5}
  - {type: elevator, name: lift, pose: [6, 0, 0], floors: {L1: 0.0, L2: 3.0}, request_policy: queue}
  - {type: agent, name: bot, pose: [0, 0, 0.1], controller: omni,
     visual_shape: {shape_type: box, half_extents: [0.2, 0.2, 0.1]}}
plugins:
  - type: workcell
    config:
      workcells:
        dispenser: {kind: dispenser, position: [1, 0]}
"""


def test_devices_and_workcells_from_a_yaml_scenario(tmp_path):
    path = tmp_path / "building.yaml"
    path.write_text(SCENARIO)
    sim = MultiRobotSimulationCore.from_yaml(path)
    try:
        by_name = {obj.name: obj for obj in sim.sim_objects}
        assert isinstance(by_name["door_1"], Door) and by_name["door_1"].open_time == 1.5
        assert isinstance(by_name["lift"], Elevator)
        assert by_name["lift"].request_policy is ElevatorRequestPolicy.QUEUE
        assert isinstance(by_name["dispenser"], Workcell)
        assert np.allclose(by_name["dispenser"].get_pose().position, [1, 0, 0])
    finally:
        sim.close()


def test_a_bad_device_entry_names_the_entry_the_key_and_the_file(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(SCENARIO.replace("open_time: 1.5", "open_tme: 1.5"))
    with pytest.raises(ValueError, match=r"bad.yaml.*entities\[0\].*'open_tme'.*'open_time'"):
        MultiRobotSimulationCore.from_yaml(path)


# ----- Gazebo worlds (the Open-RMF convention) --------------------------------------------------


WORLDS = Path(__file__).resolve().parent.parent / "data" / "worlds"


def test_open_rmf_doors_lifts_and_workcells_in_a_world_become_devices(sim):
    loaded = sim.load_world({"world_file": str(WORLDS / "rmf_devices.world")})
    by_name = {obj.name: obj for obj in loaded}
    assert list(by_name) == [
        "wall",
        "lobby_door",
        "office_door",
        "Lift1",
        "coke_dispenser",
        "coke_ingestor",
    ]
    assert type(by_name["wall"]) is SimObject
    lobby, office, lift1 = by_name["lobby_door"], by_name["office_door"], by_name["Lift1"]
    assert isinstance(lobby, Door) and isinstance(office, Door) and isinstance(lift1, Elevator)
    assert lobby.door_type.value == "sliding" and lobby.open_time == pytest.approx(1.19 / 0.4)
    assert lobby.get_pose().position.tolist() == pytest.approx([2.0, 0.0, 0.0])
    assert office.door_type.value == "hinged" and office.open_time == pytest.approx(1.57 / 0.5)
    assert lift1.floors == {"L1": 0.0, "L2": 3.0} and lift1.speed == 1.5
    assert lift1.get_pose().position.tolist() == pytest.approx([8.0, 0.0, 0.0])
    dispenser, ingestor = by_name["coke_dispenser"], by_name["coke_ingestor"]
    assert isinstance(dispenser, Workcell) and dispenser.kind.value == "dispenser"
    assert isinstance(ingestor, Workcell) and ingestor.kind.value == "ingestor"
    assert ingestor.get_pose().position.tolist() == pytest.approx([7.0, 2.0, 3.0])


def test_an_unreadable_rmf_door_is_a_named_load_failure(sim, tmp_path):
    text = (
        (WORLDS / "rmf_devices.world").read_text().replace('type="SwingDoor"', 'type="Revolving"')
    )
    world = tmp_path / "bad.world"
    world.write_text(text)
    with pytest.raises(
        WorldLoadError, match=r"'office_door': model 'office_door': door type 'Revolving'"
    ):
        sim.load_world({"world_file": str(world)})
    assert sim.sim_objects == []


def test_door_params_name_pose_and_yaw_among_the_valid_keys():
    with pytest.raises(
        ValueError, match=r"'pos' \(did you mean 'pose'\?\); valid keys: .*\bpose\b.*\byaw\b"
    ):
        DoorParams.from_dict({"pos": [0, 0, 0]}, source="doors.yaml")
