"""The fixed-base rule seen from a mission (issue 15): the mission API marks what it awaits, so
an awaited move on a fixed base fails with the reason, while a pick still works."""

from __future__ import annotations

import pytest

from fleet_async import ActionFailedError, Agent, Pose, ShapeParams, SimObject

CUBE = ShapeParams("box", half_extents=[0.03, 0.03, 0.03])


async def test_an_awaited_move_on_a_fixed_base_fails_with_the_reason(fleet_sim):
    arm = Agent.from_urdf("kuka_iiwa", use_fixed_base=True, mass=0.0, sim_core=fleet_sim)
    with pytest.raises(ActionFailedError, match="fixed base") as info:
        await arm.move(Pose.from_xyz(1, 0, 0))
    assert info.value.action.awaited


async def test_an_awaited_pick_on_a_fixed_arm_acts_from_where_it_stands(fleet_sim):
    arm = Agent.from_urdf("kuka_iiwa", use_fixed_base=True, mass=0.0, sim_core=fleet_sim)
    cube = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(0.5, 0, 0.05), sim_core=fleet_sim)
    await arm.move_joints([0.0, 0.6, 0.0, -1.2, 0.0, 0.6, 0.0])
    await arm.pick(cube, attach_link=6)
    assert cube.get_attached_parent() is arm
