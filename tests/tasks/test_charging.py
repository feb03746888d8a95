"""``await robot.charge(to=level)``: the fewest whole steps that reach it (docs/energy.md)."""

from __future__ import annotations

import pytest

from fleet_async import Agent, BatteryPlugin, Pose, ShapeParams

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def _robot(sim, **battery):
    robot = Agent.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")
    robot.add_plugin(BatteryPlugin(robot, battery))
    return robot


async def test_charging_to_a_level_takes_the_fewest_steps_that_reach_it(fleet_sim):
    robot = _robot(fleet_sim, initial_soc=0.5, charge_rate=0.01, drain_per_second=0.0001)
    charging_steps = []
    fleet_sim.events.on(
        "post_step", lambda **_: charging_steps.append(robot.battery_plugin.charging)
    )
    await robot.charge(to=0.8)
    soc = robot.battery_plugin.soc
    per_step = (0.01 - 0.0001) * fleet_sim.params.timestep
    assert soc >= 0.8 and soc - per_step < 0.8, soc  # the last step was needed
    assert sum(charging_steps) == 303  # 0.3 / 0.00099 = 303.03: 304 steps, the first unflagged
    await robot.charge(to=0.5)  # already there: a wait of 0 (it ends at the next step)
    assert robot.battery_plugin.soc >= soc - per_step


async def test_charging_to_a_level_refuses_what_cannot_be_done(fleet_sim):
    robot = _robot(fleet_sim, initial_soc=0.5, charge_rate=0.001, drain_per_second=0.002)
    with pytest.raises(ValueError, match=r"cannot reach 0\.9 by charging"):
        robot.charge(to=0.9)
    with pytest.raises(ValueError, match=r"to must be a state of charge in \[0, 1\], got 1.5"):
        robot.charge(to=1.5)
    with pytest.raises(ValueError, match="not both"):
        robot.charge(10.0, to=0.9)
    with pytest.raises(ValueError, match="not neither"):
        robot.charge()
