"""Arm awaitables in missions: move_joints / reach_pose succeed, fail and cancel (both backends)."""

from __future__ import annotations

import pytest

from fleet_async import (
    ActionCancelledError,
    ActionFailedError,
    ActionStatus,
    Agent,
    JointAction,
    Pose,
)


def arm(sim):
    return Agent.from_urdf("arm_robot", pose=Pose([0, 0, 0]), use_fixed_base=True, sim_core=sim)


async def test_move_joints_resumes_when_the_joints_arrive(fleet_sim):
    a = arm(fleet_sim)
    action = await a.move_joints({"base_to_shoulder": 0.9}, tolerance=0.001)
    # 0.9 rad at 1.5 rad/s with dt 0.1: six steps; the mission resumes at that instant.
    assert action.status is ActionStatus.COMPLETED
    assert action.end_time == pytest.approx(0.6) and fleet_sim.step_count == 6
    assert a.get_joint_state(0)[0] == pytest.approx(0.9)


async def test_move_joints_failure_raises_with_the_reason(fleet_sim):
    a = arm(fleet_sim)
    with pytest.raises(ActionFailedError, match="no joint named 'wrist'") as info:
        await a.move_joints({"wrist": 1.0})
    assert isinstance(info.value.action, JointAction)


async def test_reach_pose_reaches_or_raises(fleet_sim):
    a = arm(fleet_sim)
    action = await a.reach_pose([0.3, 0.1, 0.4])
    assert action.reachable is True and a.are_ee_at_target([0.3, 0.1, 0.4])
    with pytest.raises(ActionFailedError, match="unreachable"):
        await a.reach_pose([0.0, 3.0, 0.4])


async def test_a_timeout_cancels_the_joint_motion_and_the_arm_stops(fleet_sim):
    a = arm(fleet_sim)
    with fleet_sim.move_on_after(0.3) as scope:
        await a.move_joints([2.0, 0.0, 0.0, 0.0])
    assert scope.cancelled_caught and fleet_sim.step_count == 3
    held = a.get_joint_state(0)[0]
    assert held == pytest.approx(0.45)  # three steps of 0.15 rad
    await fleet_sim.sleep(1.0)
    assert a.get_joint_state(0)[0] == held  # nothing keeps moving for a dead mission


async def test_cancelling_the_action_from_outside_raises_in_the_mission(fleet_sim):
    a = arm(fleet_sim)
    handle = a.submit(JointAction(target_joint_positions=[1.5, 0, 0, 0]))

    async def canceller():
        await fleet_sim.sleep(0.2)
        handle.cancel()

    async with fleet_sim.task_group() as tg:
        tg.start_soon(canceller)
        with pytest.raises(ActionCancelledError):
            await handle
    assert a.get_joint_state(0)[0] == pytest.approx(0.3)
    await fleet_sim.sleep(0.5)
    assert a.get_joint_state(0)[0] == pytest.approx(0.3)
