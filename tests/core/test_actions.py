"""The action queue and the built-in actions: phases, timing, events, failures, cancellation."""

from __future__ import annotations

import itertools
import logging

import numpy as np
import pytest

from fleet_async import (
    Action,
    ActionStatus,
    Agent,
    DropAction,
    DropPhase,
    MoveAction,
    Path,
    PickAction,
    PickPhase,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    WaitAction,
)

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
SMALL = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def robot(sim, xyz=(0.0, 0.0, 0.1), controller="omni", **kw):
    return Agent.from_mesh(BOX, BOX, Pose.from_xyz(*xyz), sim_core=sim, controller=controller, **kw)


def crate(sim, xyz, **kw):
    return SimObject.from_mesh(SMALL, SMALL, Pose.from_xyz(*xyz), sim_core=sim, **kw)


def record_events(sim):
    log = []
    for name in (SimEvents.ACTION_STARTED, SimEvents.ACTION_COMPLETED, SimEvents.ACTION_FAILED):
        sim.events.on(
            name,
            lambda n=name, **kw: log.append(
                (n, type(kw["action"]).__name__, round(sim.sim_time, 9))
            ),
        )
    return log


def run_until_idle(sim, agent, max_steps=3000):
    for _ in range(max_steps):
        sim.step_once()
        if agent.is_action_queue_empty():
            return
    raise AssertionError("actions did not finish")


def test_move_action_lifecycle_timing_and_events(sim):
    agent = robot(sim)
    log = record_events(sim)
    agent_events = []
    agent.events.on(SimEvents.ACTION_COMPLETED, lambda **kw: agent_events.append(kw["action"]))
    move = MoveAction(path=Path.from_positions([[2.0, 0.0, 0.1]]))
    assert move.status is ActionStatus.NOT_STARTED and move.get_duration() is None
    agent.add_action(move)
    assert agent.get_action_queue_size() == 1 and agent.get_current_action() is None
    sim.step_once()
    assert agent.get_current_action() is move and move.status is ActionStatus.IN_PROGRESS
    assert move.start_time == 0.0
    run_until_idle(sim, agent)
    assert move.status is ActionStatus.COMPLETED and move.is_complete()
    assert agent.get_pose().position.tolist() == [2.0, 0.0, 0.1]
    # the move ends at the end of the step in which the robot arrived
    assert move.end_time == pytest.approx(sim.sim_time) and move.get_duration() == pytest.approx(
        move.end_time
    )
    assert [e[:2] for e in log] == [
        ("action_started", "MoveAction"),
        ("action_completed", "MoveAction"),
    ]
    assert agent_events == [move]


def test_wait_action_takes_exactly_its_duration(sim):
    agent = robot(sim)
    wait = WaitAction(duration=1.5)
    agent.add_action(wait)
    run_until_idle(sim, agent)
    assert (wait.start_time, wait.end_time) == (0.0, pytest.approx(1.5))
    assert wait.get_duration() == pytest.approx(1.5)


def test_sequence_starts_each_action_when_the_previous_ends(sim):
    agent = robot(sim)
    actions = [
        MoveAction(path=Path.from_positions([[1.0, 0.0, 0.1]])),
        WaitAction(duration=0.5),
        MoveAction(path=Path.from_positions([[1.0, 1.0, 0.1]])),
    ]
    agent.add_action_sequence(actions)
    run_until_idle(sim, agent)
    assert all(a.status is ActionStatus.COMPLETED for a in actions)
    for before, after in itertools.pairwise(actions):
        assert after.start_time == pytest.approx(before.end_time)
    assert actions[1].get_duration() == pytest.approx(0.5)


def test_move_action_accepts_a_pose_and_validates(sim):
    assert len(MoveAction(path=Pose.from_xyz(1, 0, 0)).path) == 1
    with pytest.raises(ValueError, match="empty path"):
        MoveAction(path=Path([]))
    with pytest.raises(ValueError, match=r"MoveAction\.direction"):
        MoveAction(path=Pose.from_xyz(1, 0, 0), direction="sideways")
    with pytest.raises(ValueError, match=r"WaitAction\.duration"):
        WaitAction(duration=-1)


def test_pick_runs_its_phases_and_attaches(sim):
    agent = robot(sim)
    target = crate(sim, (4.0, 0.0, 0.1))
    pick = PickAction(
        target_object_id=target.body_id,
        approach_offset=1.0,
        attach_relative_pose=Pose.from_xyz(0, 0, 0.3),
    )
    agent.add_action(pick)
    phases = []
    for _ in range(500):
        sim.step_once()
        if not phases or phases[-1] != pick.phase:
            phases.append(pick.phase)
        if pick.is_complete():
            break
    assert pick.status is ActionStatus.COMPLETED and pick.picked_object is target
    assert phases == [PickPhase.APPROACHING, PickPhase.MOVING_TO_PICK, PickPhase.RETREATING]
    assert target.get_attached_parent() is agent
    assert agent.get_pose().position.tolist() == pytest.approx(
        [3.0, 0.0, 0.1]
    )  # back at the approach pose
    assert target.get_pose().position.tolist() == pytest.approx([3.0, 0.0, 0.4])


def test_pick_nearest_by_position_skips_agents_and_carried_objects(sim):
    agent = robot(sim)
    robot(sim, xyz=(5.0, 0.05, 0.1))  # another robot right at the spot is not a candidate
    far = crate(sim, (5.3, 0.0, 0.1))
    near = crate(sim, (5.1, 0.0, 2.0))  # high up: found by the default 2D search only
    pick = PickAction(target_position=[5.0, 0.0, 0.1], search_radius=0.5, use_approach=False)
    agent.add_action(pick)
    run_until_idle(sim, agent)
    assert pick.picked_object is near
    other = robot(sim, xyz=(0.0, 5.0, 0.1))
    pick3d = PickAction(
        target_position=[5.0, 0.0, 0.1], search_radius=0.5, use_2d_search=False, use_approach=False
    )
    other.add_action(pick3d)
    run_until_idle(sim, other)
    assert pick3d.picked_object is far


@pytest.mark.parametrize(
    "case", ["nothing_near", "not_pickable", "already_carried", "unknown_body"]
)
def test_pick_failures_carry_a_reason(sim, case):
    agent = robot(sim)
    item = crate(sim, (2.0, 0.0, 0.1), pickable=case != "not_pickable")
    if case == "already_carried":
        robot(sim, xyz=(0, 3, 0.1)).attach_object(item)
    pick = {
        "nothing_near": PickAction(target_position=[9.0, 9.0, 0.1]),
        "not_pickable": PickAction(target_object_id=item.body_id),
        "already_carried": PickAction(target_object_id=item.body_id),
        "unknown_body": PickAction(target_object_id=999),
    }[case]
    log = record_events(sim)
    agent.add_action(pick)
    sim.step_once()
    assert pick.status is ActionStatus.FAILED
    expected = {
        "nothing_near": "no pickable object within 0.5 m",
        "not_pickable": "not pickable",
        "already_carried": "already attached",
        "unknown_body": "no object with body id 999",
    }[case]
    assert expected in pick.error_message
    assert log[-1][0] == SimEvents.ACTION_FAILED
    assert agent.get_pose().position.tolist() == [0.0, 0.0, 0.1]  # it never moved


def test_pick_then_drop_places_the_object(sim):
    agent = robot(sim, controller="differential")
    item = crate(sim, (3.0, 0.0, 0.1))
    drop = DropAction(drop_pose=Pose.from_xyz(0.0, 4.0, 0.1), approach_offset=0.5)
    agent.add_action_sequence([PickAction(target_object_id=item.body_id), drop])
    phases = []
    for _ in range(1000):
        sim.step_once()
        if drop.status is ActionStatus.IN_PROGRESS and (not phases or phases[-1] != drop.phase):
            phases.append(drop.phase)
        if agent.is_action_queue_empty():
            break
    assert drop.status is ActionStatus.COMPLETED and drop.dropped_object is item
    assert phases == [DropPhase.APPROACHING, DropPhase.MOVING_TO_DROP, DropPhase.RETREATING]
    assert not item.is_attached()
    assert item.get_pose() == Pose.from_xyz(0.0, 4.0, 0.1)
    # it backed out to the approach pose: 0.5 m from the drop point toward where it came from
    assert agent.get_pose().position.tolist() == pytest.approx(
        [0.5 / 5**0.5, 4.0 - 1.0 / 5**0.5, 0.1]
    )


def test_drop_not_gently_and_relative(sim):
    agent = robot(sim)
    a, b = crate(sim, (0, 0, 0.5)), crate(sim, (0, 0, 0.7))
    agent.attach_object(a, relative_pose=Pose.from_xyz(0, 0, 0.3))
    agent.attach_object(b, relative_pose=Pose.from_xyz(0, 0, 0.5))
    rough = DropAction(
        drop_pose=Pose.from_xyz(2, 0, 0.1),
        place_gently=False,
        drop_height=0.25,
        target_object_id=b.body_id,
        use_approach=False,
    )
    offset = DropAction(
        drop_pose=Pose.from_xyz(2, 0, 0.1),
        drop_relative_pose=Pose.from_xyz(0, 0, -0.3),
        use_approach=False,
    )
    agent.add_action_sequence([rough, offset])
    run_until_idle(sim, agent)
    assert b.get_pose().position.tolist() == pytest.approx([2, 0, 0.35])
    assert a.get_pose().position.tolist() == pytest.approx([2, 0, 0.1])  # 0.4 carried, minus 0.3


@pytest.mark.parametrize("case", ["nothing_attached", "not_ours"])
def test_drop_failures(sim, case):
    agent = robot(sim)
    item = crate(sim, (0, 2, 0.1))
    if case == "not_ours":
        agent.attach_object(crate(sim, (0, 0, 0.5)))
    drop = DropAction(
        drop_pose=Pose.from_xyz(1, 1, 0.1),
        target_object_id=item.body_id if case == "not_ours" else None,
    )
    agent.add_action(drop)
    sim.step_once()
    assert drop.status is ActionStatus.FAILED
    assert (
        "nothing is attached" if case == "nothing_attached" else "is not attached"
    ) in drop.error_message


def test_drop_requires_a_pose():
    with pytest.raises(TypeError):
        DropAction()  # type: ignore[call-arg]
    with pytest.raises(ValueError, match="drop_pose"):
        DropAction(drop_pose=[1, 2, 3])  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="target_object_id or target_position"):
        PickAction()


def test_cancel_running_move_stops_the_robot_in_that_step(sim):
    agent = robot(sim)
    log = record_events(sim)
    move, after = MoveAction(path=Pose.from_xyz(10, 0, 0.1)), WaitAction(duration=0.3)
    agent.add_action_sequence([move, after])
    for _ in range(10):
        sim.step_once()
    move.cancel()
    assert move.status is ActionStatus.CANCELLED and not agent.is_moving
    stopped_at = agent.get_pose().position.copy()
    sim.step_once()
    assert agent.get_pose().position.tolist() == stopped_at.tolist()
    assert after.status is ActionStatus.IN_PROGRESS and after.start_time == pytest.approx(1.0)
    assert ("action_failed", "MoveAction", 1.0) in log


def test_cancel_queued_action_and_clear_actions(sim):
    agent = robot(sim)
    first, second, third = (
        WaitAction(duration=1.0),
        WaitAction(duration=1.0),
        WaitAction(duration=1.0),
    )
    agent.add_action_sequence([first, second, third])
    sim.step_once()
    second.cancel()
    assert second.status is ActionStatus.CANCELLED and agent.get_action_queue_size() == 1
    agent.clear_actions()
    assert first.status is ActionStatus.CANCELLED and third.status is ActionStatus.CANCELLED
    assert agent.is_action_queue_empty()


def test_add_action_rejects_reuse_and_non_actions(sim):
    agent = robot(sim)
    wait = WaitAction(duration=0.1)
    agent.add_action(wait)
    with pytest.raises(ValueError, match="already queued"):
        agent.add_action(wait)
    run_until_idle(sim, agent)
    with pytest.raises(ValueError, match="reset"):
        agent.add_action(wait)
    wait.reset()
    agent.add_action(wait)
    run_until_idle(sim, agent)
    assert wait.status is ActionStatus.COMPLETED
    with pytest.raises(TypeError, match="Action"):
        agent.add_action("move")  # type: ignore[arg-type]


class CountTo(Action):
    """A custom action that polls: completes on its n-th execute call."""

    def __init__(self, n):
        super().__init__()
        self.n, self.calls, self.dts = n, 0, []

    def execute(self, agent, dt):
        self.calls += 1
        self.dts.append(dt)
        return self.calls >= self.n

    def reset(self):
        self._reset_status()
        self.calls = 0


def test_custom_polling_action_runs_once_per_step(sim):
    agent = robot(sim)
    action = CountTo(4)
    agent.add_action(action)
    for _ in range(3):
        sim.step_once()
    assert action.calls == 3 and action.status is ActionStatus.IN_PROGRESS
    sim.step_once()
    assert action.status is ActionStatus.COMPLETED and action.end_time == pytest.approx(0.3)
    assert action.dts == [0.1] * 4


class Explodes(Action):
    def execute(self, agent, dt):
        raise RuntimeError("boom")

    def reset(self):
        self._reset_status()


def test_an_action_that_raises_fails_loudly(sim):
    agent = robot(sim)
    action = Explodes()
    agent.add_action(action)
    with pytest.raises(RuntimeError, match="boom"):
        sim.step_once()
    assert action.status is ActionStatus.FAILED and "boom" in action.error_message


def test_removing_an_agent_drops_its_actions(sim):
    agent = robot(sim)
    move, wait = MoveAction(path=Pose.from_xyz(5, 0, 0.1)), WaitAction(duration=1.0)
    agent.add_action_sequence([move, wait])
    sim.step_once()
    sim.remove_object(agent)
    for _ in range(3):
        sim.step_once()
    assert sim.agents == []
    assert move.status is ActionStatus.CANCELLED and wait.status is ActionStatus.CANCELLED
    assert "left the simulation" in move.error_message


def test_attach_link_by_name_on_a_urdf_robot(sim):
    agent = Agent.from_urdf(
        "mobile_robot", pose=Pose.from_xyz(0, 0, 0.15), sim_core=sim, controller="omni", mass=0.0
    )
    item = crate(sim, (1.5, 0.0, 0.1))
    pick = PickAction(
        target_object_id=item.body_id,
        attach_link="sensor_mast",
        use_approach=False,
        pick_offset=0.5,
    )
    agent.add_action(pick)
    run_until_idle(sim, agent)
    assert pick.status is ActionStatus.COMPLETED
    assert agent.get_pose().position.tolist() == pytest.approx([1.0, 0.0, 0.15])
    assert item.get_pose().z > agent.get_pose().z  # rides on the mast link
    assert np.isfinite(item.get_pose().position).all()


def test_reset_cancels_unfinished_actions_with_a_reason(sim):
    agent = robot(sim)
    move, wait = MoveAction(path=Pose.from_xyz(5, 0, 0.1)), WaitAction(duration=1.0)
    agent.add_action_sequence([move, wait])
    failed = []
    sim.events.on(
        SimEvents.ACTION_FAILED, lambda **kw: failed.append((kw["agent"].object_id, kw["action"]))
    )
    sim.step_once()
    object_id = agent.object_id
    sim.reset()
    assert move.status is ActionStatus.CANCELLED and wait.status is ActionStatus.CANCELLED
    assert "reset" in move.error_message
    assert failed == [(object_id, move), (object_id, wait)]


def test_a_queued_move_on_a_fixed_base_is_skipped_with_a_warning(sim, caplog):
    # Seed, agent.set_goal_pose: "This is ignored if the robot has a fixed base".
    fixed = robot(sim, use_fixed_base=True)
    move = MoveAction(path=Pose.from_xyz(3, 0, 0.1))
    wait = WaitAction(duration=0.2)
    fixed.add_action_sequence([move, wait])
    with caplog.at_level(logging.WARNING):
        sim.step_once()
    assert move.status is ActionStatus.COMPLETED and move.error_message is None
    assert (move.start_time, move.end_time) == (0.0, 0.0)
    assert "MoveAction skipped" in caplog.text and "fixed base" in caplog.text
    assert fixed.get_pose().x == 0.0 and fixed.get_current_action() is wait


def test_an_awaited_move_on_a_fixed_base_fails_with_the_reason(sim):
    # The mission API marks what it submits as awaited, so the mission sees why.
    fixed = robot(sim, use_fixed_base=True)
    move = MoveAction(path=Pose.from_xyz(3, 0, 0.1))
    move.awaited = True
    fixed.add_action(move)
    sim.step_once()
    assert move.status is ActionStatus.FAILED and "fixed base" in move.error_message


def test_moves_fail_with_a_reason_when_the_agent_has_no_base_controller(sim):
    frozen = robot(sim, xyz=(0.0, 5.0, 0.1))
    frozen.set_controller(None)
    pick = PickAction(target_object_id=crate(sim, (3.0, 5.0, 0.1)).body_id)
    frozen.add_action(pick)
    sim.step_once()
    assert pick.status is ActionStatus.FAILED and "no base controller" in pick.error_message
