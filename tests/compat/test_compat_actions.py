"""Seed behaviours of actions (issue 15): each test quotes the seed text it checks.

The seed is the reference API's documentation (``shared/seed/000_3dffb1b59eacdbf9.txt``).
"""

from __future__ import annotations

import logging

import pytest

from fleet_async.action import (
    Action,
    DropAction,
    JointAction,
    MoveAction,
    PickAction,
    WaitAction,
)
from fleet_async.agent import Agent
from fleet_async.events import SimEvents
from fleet_async.geometry import Path, Pose
from fleet_async.sim_object import ShapeParams, SimObject
from fleet_async.types import ActionStatus

BOX = ShapeParams("box", half_extents=[0.2, 0.15, 0.1])
CUBE = ShapeParams("box", half_extents=[0.03, 0.03, 0.03])
DT = 0.1


def omni(sim, x=0.0, y=0.0, **kw):
    return Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(x, y, 0.1), sim_core=sim, controller="omni", **kw
    )


# Action: "Each action manages its own state and returns True when complete";
# execute(agent, dt): "Execute action for one timestep".


def test_wait_action_run_directly_counts_the_dt_it_is_given(sim):
    agent = omni(sim)
    action = WaitAction(duration=1.0)
    calls = 0
    while not action.is_complete():
        done = action.execute(agent, DT)
        calls += 1
        assert done is action.is_complete()
    assert calls == 10  # 10 x 0.1 s cover 1.0 s
    assert action.status is ActionStatus.COMPLETED
    assert (action.start_time, action.end_time) == (0.0, 0.0)  # nothing stepped the clock
    assert action.get_duration() == 0.0
    action.reset()
    assert action.status is ActionStatus.NOT_STARTED and action.start_time is None
    assert action.execute(agent, 2.0) is True  # one call of 2 s covers it


def test_status_and_times_are_set_when_an_action_is_run_directly(sim):
    agent = omni(sim)
    action = MoveAction(path=Path.from_positions([[1.0, 0.0, 0.1]]))
    assert action.status is ActionStatus.NOT_STARTED
    action.execute(agent, DT)
    assert action.status is ActionStatus.IN_PROGRESS and action.start_time == 0.0
    calls = 1
    while not action.is_complete():
        sim.step_once()
        action.execute(agent, DT)
        calls += 1
    assert action.status is ActionStatus.COMPLETED
    assert action.end_time == pytest.approx(sim.sim_time)
    assert agent.get_pose().position.tolist() == [1.0, 0.0, 0.1]
    assert calls == 10  # 1 m at 2 m/s, 5 m/s^2: 0.4 + 0.5 s, 9 steps, seen on the 10th call


def test_agent_update_moves_the_agent_in_a_custom_loop(sim):
    # Agent.update(dt): "Update robot position towards goal with velocity/acceleration
    # constraints"; a user's own loop calls it instead of step_once.
    agent = omni(sim)
    action = MoveAction(path=Path.from_positions([[1.0, 0.0, 0.1]]))
    calls = 0
    while not action.is_complete() and calls < 100:
        action.execute(agent, DT)
        agent.update(DT)
        calls += 1
    assert action.status is ActionStatus.COMPLETED and calls == 10
    assert agent.get_pose().position.tolist() == [1.0, 0.0, 0.1]
    assert sim.step_count == 0


def test_agent_update_inside_a_step_does_not_move_twice(sim):
    class Counting(Agent):
        calls = 0

        def update(self, dt):
            Counting.calls += 1
            super().update(dt)  # the seed's pattern: extend update, keep the motion

    agent = Counting.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")
    plain = omni(sim, y=3.0)
    for robot in (agent, plain):
        robot.set_goal_pose(Pose.from_xyz(2.0, robot.get_pose().y, 0.1))
    for _ in range(5):
        sim.step_once()
    assert Counting.calls == 5
    assert agent.get_pose().x == plain.get_pose().x == pytest.approx(0.6)


def test_a_custom_action_keeps_working_from_the_queue(sim):
    class Beep(Action):
        def __init__(self):
            super().__init__()
            self.calls = 0

        def execute(self, agent, dt):
            self.calls += 1
            return self.calls == 3

        def reset(self):
            self.calls = 0

    agent = omni(sim)
    beep = Beep()
    agent.add_action(beep)
    for _ in range(3):
        sim.step_once()
    assert beep.status is ActionStatus.COMPLETED and beep.start_time == 0.0
    assert beep.end_time == pytest.approx(0.2)


# PickAction: "approach_offset - Auto-calculate approach offset distance"; tools example:
# "Approach pose (1.5m away from target)".


def test_approach_offset_is_the_distance_from_the_target(sim):
    agent = omni(sim)
    crate = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(5.0, 0.0, 0.1), sim_core=sim)
    pick = PickAction(target_object_id=crate.body_id, approach_offset=1.0, pick_offset=0.3)
    agent.add_action(pick)
    xs = []
    while not pick.is_complete():
        sim.step_once()
        xs.append(round(agent.get_pose().x, 9))
    assert pick.status is ActionStatus.COMPLETED and crate.is_attached()
    # Drive to the approach pose (target - approach_offset), in to the pick pose (target -
    # pick_offset), and back out to the approach pose; each sub-move lands exactly.
    turn = xs.index(4.7)
    assert 4.0 in xs[:turn] and xs[:turn] == sorted(xs[:turn])
    assert max(xs) == 4.7 and xs[-1] == 4.0


# agent.set_goal_pose: "This is ignored if the robot has a fixed base"; update: "does nothing
# if the robot has a fixed base".


def test_a_fixed_arm_picks_and_drops_from_where_it_stands(sim, caplog):
    arm = Agent.from_urdf("kuka_iiwa", use_fixed_base=True, mass=0.0, sim_core=sim)
    cube = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(0.5, 0.0, 0.05), sim_core=sim)
    actions = [
        JointAction(target_joint_positions=[0.0, 0.6, 0.0, -1.2, 0.0, 0.6, 0.0]),
        PickAction(target_object_id=cube.body_id, attach_link=6),
        MoveAction(path=Pose.from_xyz(1.0, 0.0, 0.0)),
        DropAction(drop_pose=Pose.from_xyz(0.4, 0.3, 0.05)),
    ]
    base = arm.get_pose().position.tolist()
    arm.add_action_sequence(actions)
    with caplog.at_level(logging.WARNING):
        for _ in range(100):
            sim.step_once()
            if arm.is_action_queue_empty():
                break
    assert [a.status for a in actions] == [ActionStatus.COMPLETED] * 4
    assert "MoveAction skipped" in caplog.text
    assert arm.get_pose().position.tolist() == base
    assert not cube.is_attached()
    assert cube.get_pose().position.tolist() == pytest.approx([0.4, 0.3, 0.05])


# pybullet_fleet 0.8.0's PickAction / DropAction refuse joint_targets together with
# ee_target_position (a ValueError when the action is made), and leave the arm where the reach
# took it: at the joint targets, or at the IK solution for the end-effector target.


@pytest.mark.parametrize(
    "make",
    [
        lambda **arm: PickAction(target_object_id=1, **arm),
        lambda **arm: DropAction(drop_pose=Pose.from_xyz(0, 0.4, 0.05), **arm),
    ],
    ids=["pick", "drop"],
)
def test_joint_targets_and_an_end_effector_target_are_refused_together(make):
    with pytest.raises(ValueError, match=r"joint_targets.*ee_target_position.*not both") as info:
        make(joint_targets={"shoulder_to_elbow": 1.0}, ee_target_position=[0.4, 0.0, 0.2])
    assert "Action" in str(info.value) and "[0.4, 0.0, 0.2]" in str(info.value)
    with pytest.raises(ValueError, match="not both"):  # an empty mapping is still given
        make(joint_targets={}, ee_target_position=[0.4, 0.0, 0.2])
    make(joint_targets=[0.1, 0.2, 0.0, 0.0])
    make(ee_target_position=[0.4, 0.0, 0.2])


def _joint_positions(arm):
    return [arm.get_joint_state_by_name(n)[0] for n in arm.joint_names]


def test_arm_pick_and_drop_leave_the_arm_at_the_targets(sim):
    arm = Agent.from_urdf("arm_robot", use_fixed_base=True, sim_core=sim)
    box = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(0.5, 0.0, 0.2), sim_core=sim)
    low = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(0.45, 0.0, 0.05), sim_core=sim)
    pick_at = {"shoulder_to_elbow": 1.0}
    arrived = []

    def note_arrival(sim, **_):
        if not arrived and arm.are_joints_at_targets(pick_at, 0.001):
            arrived.append(sim.sim_time)

    sim.events.on(SimEvents.POST_STEP, note_arrival)
    pick = PickAction(target_object_id=box.body_id, joint_targets=pick_at, joint_tolerance=0.001)
    drop = DropAction(
        drop_pose=Pose.from_xyz(0.0, 0.45, 0.05),
        joint_targets={"base_to_shoulder": 1.5, "shoulder_to_elbow": 0.5},
        joint_tolerance=0.001,
    )
    arm.add_action_sequence([pick, drop])
    while not pick.is_complete():
        sim.step_once()
    assert pick.status is ActionStatus.COMPLETED and box.get_attached_parent() is arm
    assert arrived == [pick.end_time]  # done in the step the reach ended: no lift after it
    while not drop.is_complete():
        sim.step_once()
    assert drop.status is ActionStatus.COMPLETED and not box.is_attached()
    for _ in range(10):
        sim.step_once()
    assert _joint_positions(arm) == pytest.approx([1.5, 0.5, 0.0, 0.0], abs=0.001)
    reach = PickAction(target_object_id=low.body_id, ee_target_position=[0.45, 0.0, 0.1])
    arm.add_action(reach)
    for _ in range(60):
        sim.step_once()
    assert reach.status is ActionStatus.COMPLETED and low.get_attached_parent() is arm
    assert arm.are_ee_at_target([0.45, 0.0, 0.1])  # still reaching: not lifted back
