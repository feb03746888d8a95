"""Safety fields: protective stops, warning slow-downs, events, deadlock suspicion, stats."""

from __future__ import annotations

import pytest

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
)
from fleet_async.core.collision.safety_deadlock import DeadlockWatch, blocked_sets
from fleet_async.core.collision.safety_params import SafetyFieldParams
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.2])


def robot(sim, x, y=0.0, name=None, fields=True, yaw=0.0):
    params = AgentSpawnParams(
        visual_shape=BOX,
        collision_shape=BOX,
        initial_pose=Pose.from_euler(x, y, 0.2, 0.0, 0.0, yaw),
        name=name,
        motion_mode="omnidirectional",
        safety_field=fields,
    )
    return Agent.from_params(params, sim)


def wall(sim, x, y=0.0, name="wall"):
    return SimObject.from_mesh(BOX, BOX, Pose.from_xyz(x, y, 0.2), sim_core=sim, name=name)


def make_sim():
    return MultiRobotSimulationCore(headless_params(enable_floor=True))


def record(sim):
    log = []

    def started(agent, obstacles, **_):
        log.append(("start", sim.step_count, agent.name, [o.name for o in obstacles]))

    def ended(agent, duration, **_):
        log.append(("end", sim.step_count, agent.name, round(duration, 9)))

    sim.events.on(SimEvents.SAFETY_STOP_STARTED, started)
    sim.events.on(SimEvents.SAFETY_STOP_ENDED, ended)
    return log


def test_fields_are_off_by_default_and_a_robot_drives_through():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a", fields=None)
        wall(sim, 3.0)
        log = record(sim)
        a.set_path([Pose.from_xyz(5.0, 0.0, 0.2)])
        for _ in range(40):
            sim.step_once()
        assert not sim.safety.enabled
        assert sim.safety.params_of(a) is None
        assert log == []
        assert a.get_pose().position[0] == pytest.approx(5.0)


def test_a_wall_ahead_slows_then_stops_the_robot_and_it_resumes_when_cleared():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a")
        w = wall(sim, 3.0)
        log = record(sim)
        a.set_path([Pose.from_xyz(5.0, 0.0, 0.2)])
        for _ in range(40):
            sim.step_once()
        assert sim.safety.is_stopped(a)
        assert a.is_moving  # the path stays active while the robot is stopped
        front = a.get_pose().position[0] + 0.3
        assert 2.7 - front <= 0.1 + 1e-9  # stopped within its standstill protective depth
        sim.remove_object(w)
        for _ in range(30):
            sim.step_once()
        assert a.get_pose().position[0] == pytest.approx(5.0)
        assert not a.is_moving
    starts = [e for e in log if e[0] == "start"]
    ends = [e for e in log if e[0] == "end"]
    assert all(e[3] == ["wall"] for e in starts)
    assert len(starts) == len(ends) >= 1
    assert log[-1][0] == "end" and log[-1][1] == 40  # in the first step after the wall left
    stops, stopped = sim.safety.stats()[a.object_id]
    assert stops == len(starts)
    assert stopped == pytest.approx(sum(e[3] for e in ends))


def test_the_warning_field_slows_the_robot_to_its_slow_factor():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a", fields={"warning_margin": 3.0, "slow_factor": 0.25})
        wall(sim, 6.0)
        a.set_path([Pose.from_xyz(4.0, 0.0, 0.2)])
        speeds = []
        for _ in range(30):
            sim.step_once()
            speeds.append(float(a.velocity[0]))
        assert max(speeds) <= 2.0 + 1e-9
        assert min(s for s in speeds[3:12]) < 2.0  # slowed while the wall is in the warning field


def test_head_on_robots_stop_and_a_deadlock_is_suspected_once():
    with make_sim() as sim:
        sim.safety.deadlock_after = 2.0
        a = robot(sim, 0.0, name="a")
        b = robot(sim, 4.0, name="b", yaw=3.141592653589793)
        deadlocks = []
        sim.events.on(
            SimEvents.DEADLOCK_SUSPECTED,
            lambda agents, sim_time, **_: deadlocks.append(([x.name for x in agents], sim_time)),
        )
        a.set_path([Pose.from_xyz(4.0, 0.0, 0.2)])
        b.set_path([Pose.from_xyz(0.0, 0.0, 0.2)])
        for _ in range(100):
            sim.step_once()
        assert sim.safety.stopped_agents() == [a, b]
        assert a.is_moving and b.is_moving
        assert len(deadlocks) == 1
        assert deadlocks[0][0] == ["a", "b"]
        assert sim.safety.deadlocks_suspected == 1
        gap = b.get_pose().position[0] - a.get_pose().position[0] - 0.6
        assert 0.0 < gap <= 0.2 + 1e-9
        assert sim.collision_count == 0


def test_a_robot_waiting_behind_another_is_no_deadlock():
    with make_sim() as sim:
        sim.safety.deadlock_after = 0.5
        a = robot(sim, 0.0, name="a")
        robot(sim, 1.2, name="parked")  # stands still: no field in force, not stopped
        deadlocks = []
        sim.events.on(SimEvents.DEADLOCK_SUSPECTED, lambda agents, **_: deadlocks.append(agents))
        a.set_path([Pose.from_xyz(4.0, 0.0, 0.2)])
        for _ in range(50):
            sim.step_once()
        assert sim.safety.stopped_agents() == [a]
        assert deadlocks == []


def test_what_the_robot_carries_is_no_obstacle():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a")
        tote = SimObject.from_mesh(
            ShapeParams("box", half_extents=[0.45, 0.2, 0.1]),
            ShapeParams("box", half_extents=[0.45, 0.2, 0.1]),
            Pose.from_xyz(0.1, 0.0, 0.3),
            sim_core=sim,
            name="tote",
        )
        tote.pickable = True
        assert a.attach_object(tote)
        log = record(sim)
        a.set_path([Pose.from_xyz(3.0, 0.0, 0.2)])
        for _ in range(30):
            sim.step_once()
        assert log == []
        assert a.get_pose().position[0] == pytest.approx(3.0)


def test_fields_can_be_given_and_taken_after_spawning():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a", fields=None)
        wall(sim, 2.0)
        sim.safety.enable(a, {"protective_margin": 0.3})
        assert sim.safety.params_of(a) == SafetyFieldParams(protective_margin=0.3)
        a.set_path([Pose.from_xyz(5.0, 0.0, 0.2)])
        for _ in range(30):
            sim.step_once()
        assert sim.safety.is_stopped(a)
        assert sim.safety.disable(a)
        assert not sim.safety.disable(a)
        sim.step_once()
        assert not sim.safety.is_stopped(a)
        oid = a.object_id
        sim.remove_object(a)
        sim.step_once()
        assert oid in sim.safety.stats()


def test_a_removed_robot_leaves_the_fields():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a")
        sim.step_once()
        sim.remove_object(a)
        sim.step_once()
        assert not sim.safety.enabled


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ({"deceleration": 0}, "deceleration"),
        ({"slow_factor": 1.5}, "slow_factor"),
        ({"footprint": [1.0]}, "footprint"),
        ({"bogus": 1}, "bogus"),
        ("yes", "safety_field"),
    ],
)
def test_bad_field_settings_are_refused_by_name(value, message):
    with pytest.raises(ValueError, match=message):
        AgentSpawnParams(safety_field=value)


def test_spawn_params_from_a_mapping():
    params = AgentSpawnParams.from_dict(
        {"safety_field": {"deceleration": 2.0, "footprint": [0.8, 0.5]}}
    )
    assert params.safety_field == SafetyFieldParams(deceleration=2.0, footprint=(0.8, 0.5))
    assert SafetyFieldParams().protective_depth(2.0) == pytest.approx(2.1)
    assert SafetyFieldParams().warning_depth(0.0) == pytest.approx(0.6)


def test_blocked_sets_keep_only_robots_held_by_a_member():
    held_by = {1: {2}, 2: {1}, 3: {1}, 4: {9}, 5: {6}, 6: set(), 7: {8}, 8: {7}}
    assert blocked_sets(held_by) == [frozenset({1, 2, 3}), frozenset({7, 8})]


def test_the_deadlock_watch_reports_a_set_once_after_its_time():
    watch = DeadlockWatch(1.0)
    s = frozenset({1, 2})
    assert [watch.update([s], step, 0.1) for step in range(12)].count([s]) == 1
    assert watch.update([s], 12, 0.1) == []
    assert watch.update([], 13, 0.1) == []
    assert watch.update([s], 14, 0.1) == []
    assert watch.count == 1
    with pytest.raises(ValueError, match="deadlock_after"):
        watch.deadlock_after = 0


def test_kpis_count_stops_time_stopped_and_deadlocks():
    with make_sim() as sim:
        sim.safety.deadlock_after = 2.0
        kpis = sim.kpis()
        a = robot(sim, 0.0, name="a")
        b = robot(sim, 4.0, name="b", yaw=3.141592653589793)
        a.set_path([Pose.from_xyz(4.0, 0.0, 0.2)])
        b.set_path([Pose.from_xyz(0.0, 0.0, 0.2)])
        for _ in range(100):
            sim.step_once()
        stats = sim.safety.stats()
        rows = {r.robot: r for r in kpis.per_robot()}
        assert (rows["a"].safety_stops, rows["a"].safety_stopped_time_s) == stats[a.object_id]
        assert rows["b"].safety_stops == stats[b.object_id][0] >= 1
        summary = kpis.summary()
        assert summary.safety_stops == rows["a"].safety_stops + rows["b"].safety_stops
        assert summary.safety_stopped_time_total_s == pytest.approx(
            rows["a"].safety_stopped_time_s + rows["b"].safety_stopped_time_s
        )
        assert summary.deadlocks_suspected == 1
        kpis.stop()
        for _ in range(10):
            sim.step_once()
        assert kpis.summary().safety_stopped_time_total_s == summary.safety_stopped_time_total_s


def test_a_stopped_robot_sent_the_other_way_drives_off():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a")
        b = robot(sim, 4.0, name="b", yaw=3.141592653589793)
        a.set_path([Pose.from_xyz(4.0, 0.0, 0.2)])
        b.set_path([Pose.from_xyz(0.0, 0.0, 0.2)])
        for _ in range(60):
            sim.step_once()
        assert sim.safety.stopped_agents() == [a, b]
        x = a.get_pose().x
        a.set_path([Pose.from_xyz(-2.0, 0.0, 0.2)])  # traffic control backs a off
        for _ in range(40):
            sim.step_once()
        assert a.get_pose().x == pytest.approx(-2.0) and x > -2.0
        assert b.get_pose().x < 4.0 - 1.0  # b drove on once a had made room


def test_a_robot_does_not_start_into_an_obstacle_within_its_margin():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a")
        wall(sim, 0.65)  # 0.05 m ahead of the footprint: inside the 0.1 m margin
        log = record(sim)
        a.set_path([Pose.from_xyz(3.0, 0.0, 0.2)])
        for _ in range(10):
            sim.step_once()
        assert a.get_pose().x == 0.0
        assert log == [("start", 0, "a", ["wall"])]


def test_a_blocked_set_that_breaks_up_and_forms_again_is_timed_from_its_return():
    with make_sim() as sim:
        sim.safety.deadlock_after = 5.0
        a = robot(sim, 0.0, name="a")
        b = robot(sim, 4.0, name="b", yaw=3.141592653589793)
        times, stops = [], []
        sim.events.on(
            SimEvents.DEADLOCK_SUSPECTED, lambda sim_time, **_: times.append(round(sim_time, 9))
        )
        sim.events.on(SimEvents.SAFETY_STOP_STARTED, lambda **_: stops.append(sim.sim_time))
        a.set_path([Pose.from_xyz(4.0, 0.0, 0.2)])
        b.set_path([Pose.from_xyz(0.0, 0.0, 0.2)])
        while len(sim.safety.stopped_agents()) < 2:
            sim.step_once()
        for _ in range(30):
            sim.step_once()
        a.stop()  # the pair breaks up: a no longer waits, b waits for a robot that may drive on
        for _ in range(5):
            sim.step_once()
        assert sim.safety.stopped_agents() == [b]
        a.set_path([Pose.from_xyz(4.0, 0.0, 0.2)])
        while len(sim.safety.stopped_agents()) < 2:
            sim.step_once()
        formed_again = stops[-1]  # a's stop that closes the set again
        for _ in range(80):
            sim.step_once()
        assert times == [round(formed_again + 5.0, 9)]  # 9.9 s; timed from 1.3 s it came at 6.3
