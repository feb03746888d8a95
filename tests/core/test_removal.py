"""Using an object after it left its simulation raises an error naming it (bodies/removal.py)."""

from __future__ import annotations

import pytest

import fleet_async as fa
from fleet_async import Agent, ObjectRemovedError, Pose, ShapeParams, SimObject

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def robot(sim, name="r0"):
    return Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni", name=name
    )


@pytest.mark.parametrize(
    "use",
    [
        lambda r: r.get_pose(),
        lambda r: r.set_pose(Pose.from_xyz(1, 0, 0.1)),
        lambda r: r.set_path([Pose.from_xyz(1, 0, 0.1)]),
        lambda r: r.set_goal_pose(Pose.from_xyz(1, 0, 0.1)),
        lambda r: r.add_action(fa.WaitAction(duration=1.0)),
        lambda r: r.attach_object(r),
    ],
    ids=["get_pose", "set_pose", "set_path", "set_goal_pose", "add_action", "attach_object"],
)
def test_a_removed_robot_raises_on_use_naming_it(sim, use):
    r = robot(sim, "picker3")
    sim.step_once()
    sim.remove_object(r)
    with pytest.raises(ObjectRemovedError, match=r"name='picker3'.*removed from its simulation"):
        use(r)


def test_the_message_says_when_and_what_to_do(sim):
    box = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, name="crate")
    for _ in range(3):
        sim.step_once()
    sim.remove_object(box)
    with pytest.raises(ObjectRemovedError) as info:
        box.get_pose()
    message = str(info.value)
    assert "at sim time 0.300 s" in message
    assert "sim.remove_object" in message
    assert "spawn a new one" in message


def test_removal_handlers_still_see_the_last_pose(sim):
    box = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(2, 1, 0.1), sim_core=sim)
    seen = []
    sim.events.on(fa.SimEvents.OBJECT_REMOVED, lambda obj, **_: seen.append(obj.get_pose().x))
    sim.remove_object(box)
    assert seen == [2.0]


def test_a_standalone_object_is_not_a_removed_one():
    # An object created without a simulation keeps working on its own (the reference API).
    box = SimObject(body_id=-1)
    box.set_pose(Pose.from_xyz(1, 2, 3))
    assert box.get_pose().y == 2


async def test_moving_a_removed_robot_in_a_mission_names_it(fleet_sim):
    r = robot(fleet_sim, "picker5")
    await fleet_sim.sleep(0.5)
    fleet_sim.remove_object(r)
    with pytest.raises(ObjectRemovedError, match=r"agent.move: .*'picker5'.*removed"):
        await r.move(Pose.from_xyz(3, 0, 0.1))


async def test_charging_without_a_battery_says_how_to_add_one(fleet_sim):
    r = robot(fleet_sim)
    with pytest.raises(ValueError, match="has no battery") as info:
        await r.charge(5.0)
    assert "plugins: [{type: battery" in str(info.value)
    assert "BatteryPlugin" in str(info.value)
    assert fleet_sim.sim_time == 0.0  # nothing was queued


async def test_charging_with_a_battery_charges(fleet_sim):
    r = robot(fleet_sim)
    r.add_plugin(fa.BatteryPlugin(r, {"initial_soc": 0.5, "charge_rate": 0.1}))
    await r.charge(1.0)
    assert r.battery_soc > 0.55
