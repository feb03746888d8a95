"""Fleet KPIs on tiny deterministic scenes, with exact figures."""

from __future__ import annotations

import sys

import pytest

import fleet_async as fa
from fleet_async import (
    ActionStatus,
    Agent,
    AgentSpawnParams,
    FleetKpis,
    MoveAction,
    Pose,
    RobotKpis,
    ShapeParams,
    SimEvents,
    WaitAction,
)

if sys.version_info < (3, 11):
    from exceptiongroup import BaseExceptionGroup

DT = 0.1
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def robot(sim, x=0.0, y=0.0, name=None, plugins=None, vmax=1.0):
    params = AgentSpawnParams(
        visual_shape=BOX,
        collision_shape=BOX,
        initial_pose=Pose.from_xyz(x, y, 0.1),
        controller={"type": "omni", "max_linear_vel": vmax, "max_linear_accel": 10.0},
        name=name,
        plugins=plugins,
    )
    return Agent.from_params(params, sim)


def steps(sim, n):
    for _ in range(n):
        sim.step_once()


def test_one_robot_moves_waits_and_idles(sim):
    r = robot(sim, name="r0")
    kpis = sim.kpis()
    move, wait = MoveAction(path=Pose.from_xyz(2.0, 0.0, 0.1)), WaitAction(duration=1.0)
    r.add_action_sequence([move, wait])
    steps(sim, 50)
    # 2 m at 1 m/s and 10 m/s^2: the exact trapezoid takes 0.1 s to reach 1 m/s and 0.1 s to
    # brake, 2.1 s in all, so 21 steps moving (the move ends with step 21, at t = 2.1 s); the
    # wait starts at the next tick and covers steps 22..31, then 19 idle steps.
    assert (move.start_time, move.end_time) == (0.0, 2.1)
    assert (wait.start_time, wait.end_time) == (2.1, pytest.approx(3.1))
    row = kpis.summary()
    assert (row.robot_count, row.steps, row.sim_time_s) == (1, 50, 50 * DT)
    assert row.moving_time_total_s == 21 * DT
    assert row.waiting_time_total_s == 10 * DT
    assert row.idle_time_total_s == 19 * DT
    assert row.distance_total_m == pytest.approx(2.0, abs=1e-12)
    assert (row.actions_completed, row.actions_failed, row.actions_cancelled) == (2, 0, 0)
    assert (row.collisions, row.mission_errors, row.tasks_completed) == (0, 0, 0)
    assert row.battery_robots == 0 and row.battery_used_total is None
    (detail,) = kpis.per_robot()
    assert detail.robot == "r0" and detail.object_id == r.object_id
    assert (detail.moving_time_s, detail.waiting_time_s, detail.idle_time_s) == (
        21 * DT,
        10 * DT,
        19 * DT,
    )


def test_fleet_means_divide_by_robots(sim):
    a, b = robot(sim, 0.0, 0.0), robot(sim, 0.0, 5.0)
    kpis = sim.kpis()
    a.add_action(MoveAction(path=Pose.from_xyz(2.0, 0.0, 0.1)))
    steps(sim, 30)
    row = kpis.summary()
    assert row.robot_count == 2
    assert row.moving_time_total_s == 21 * DT and row.moving_time_mean_s == 21 * DT / 2
    assert row.idle_time_total_s == 39 * DT and row.idle_time_mean_s == 39 * DT / 2
    assert row.distance_mean_m == pytest.approx(1.0, abs=1e-12)
    assert [d.idle_time_s for d in kpis.per_robot()] == [9 * DT, 30 * DT]
    assert b.get_pose().x == 0.0


def test_cancelled_and_failed_actions(sim):
    r = robot(sim)
    kpis = sim.kpis()
    move = MoveAction(path=Pose.from_xyz(5.0, 0.0, 0.1))
    r.add_action(move)
    steps(sim, 5)
    move.cancel()  # between steps: the robot stops now, the action ends at t = 0.5 s
    steps(sim, 5)
    r.use_fixed_base = True  # a fixed base refuses to move: an awaited move fails
    blocked = MoveAction(path=Pose.from_xyz(1.0, 0.0, 0.1))
    blocked.awaited = True  # as agent.submit marks it (a plain queued one is skipped)
    r.add_action(blocked)
    steps(sim, 1)
    assert move.status is ActionStatus.CANCELLED and blocked.status is ActionStatus.FAILED
    row = kpis.summary()
    assert (row.actions_completed, row.actions_failed, row.actions_cancelled) == (0, 2, 1)
    assert row.moving_time_total_s == 5 * DT and row.idle_time_total_s == 6 * DT
    (detail,) = kpis.per_robot()
    assert (detail.actions_failed, detail.actions_cancelled) == (2, 1)


def test_tasks_and_throughput(sim):
    r = robot(sim)
    kpis = sim.kpis()

    def report(sim, dt):  # three tasks done and one given up on, over 60 s
        if sim.step_count in (100, 200, 300):
            sim.events.emit(SimEvents.TASK_COMPLETED, sim=sim, agent=r, task=sim.step_count)
        if sim.step_count == 400:
            sim.events.emit(SimEvents.TASK_FAILED, sim=sim, agent=None, task="lost")

    sim.register_callback(report)
    steps(sim, 600)
    row = kpis.summary()
    assert (row.tasks_completed, row.tasks_failed) == (3, 1)
    assert row.sim_time_s == 60.0 and row.throughput_per_hour == 3 * 60.0
    (detail,) = kpis.per_robot()
    assert (detail.tasks_completed, detail.tasks_failed) == (3, 0)


def test_collisions_started_count_once_per_pair(sim):
    a, b = robot(sim, 0.0, name="a"), robot(sim, 3.0, name="b")
    kpis = sim.kpis()
    a.add_action(MoveAction(path=Pose.from_xyz(1.5, 0.0, 0.1)))
    b.add_action(MoveAction(path=Pose.from_xyz(1.5, 0.0, 0.1)))
    steps(sim, 40)
    row = kpis.summary()
    assert row.collisions == 1 == sim.collision_count
    assert [d.collisions for d in kpis.per_robot()] == [1, 1]


def test_battery_used_and_lowest_charge(sim):
    battery = {"type": "battery", "config": {"drain_per_meter": 0.1, "drain_per_second": 0.0}}
    r = robot(sim, plugins=[battery])
    robot(sim, 0.0, 5.0)  # no battery: not counted in the battery figures
    kpis = sim.kpis()
    r.add_action(MoveAction(path=Pose.from_xyz(2.0, 0.0, 0.1)))
    steps(sim, 30)
    row = kpis.summary()
    assert row.battery_robots == 1
    assert row.battery_used_total == pytest.approx(0.2, abs=1e-12)
    assert row.battery_used_mean == row.battery_used_total
    assert row.battery_min_soc == pytest.approx(0.8, abs=1e-12)
    with_battery, without = kpis.per_robot()
    assert with_battery.battery_soc == r.battery_soc
    assert without.battery_used is None and without.battery_soc is None


def test_charging_does_not_undo_battery_used(sim):
    config = {"initial_soc": 0.5, "drain_per_meter": 0.0, "drain_per_second": 0.01}
    r = robot(sim, plugins=[{"type": "battery", "config": {**config, "charge_rate": 0.05}}])
    kpis = sim.kpis()
    r.add_action(WaitAction(duration=2.0, action_type="charge"))
    steps(sim, 20)
    (detail,) = kpis.per_robot()
    assert detail.battery_used == pytest.approx(0.01 * 2.0, abs=1e-12)
    assert detail.battery_soc == pytest.approx(0.5 + 0.04 * 2.0, abs=1e-12)
    assert detail.waiting_time_s == 20 * DT  # charging in place is waiting


def test_removed_robot_keeps_its_figures(sim):
    a, b = robot(sim, name="a"), robot(sim, 0.0, 5.0, name="b")
    kpis = sim.kpis()
    a.add_action(MoveAction(path=Pose.from_xyz(1.0, 0.0, 0.1)))
    steps(sim, 5)
    sim.remove_object(a)  # its move ends CANCELLED (ACTION_FAILED)
    steps(sim, 5)
    late = robot(sim, 0.0, -5.0, name="late")
    steps(sim, 3)
    details = {d.robot: d for d in kpis.per_robot()}
    assert list(details) == ["a", "b", "late"]
    assert details["a"].moving_time_s == 5 * DT and details["a"].idle_time_s == 0.0
    assert details["a"].actions_cancelled == 1
    assert details["b"].idle_time_s == 13 * DT
    assert details["late"].idle_time_s == 3 * DT
    assert kpis.summary().robot_count == 3 and b.sim_core is sim and late.sim_core is sim


def test_counts_start_when_asked_and_stop_freezes(sim):
    r = robot(sim)
    r.add_action(MoveAction(path=Pose.from_xyz(2.0, 0.0, 0.1)))
    steps(sim, 10)
    kpis = sim.kpis(from_now=True)
    assert sim.kpis() is kpis
    steps(sim, 20)
    kpis.stop()
    steps(sim, 10)
    row = kpis.summary()
    assert row.steps == 20 and row.sim_time_s == 20 * DT
    # the move ends with step 21: steps 11..21 of it are counted
    assert row.moving_time_total_s == 11 * DT and row.actions_completed == 1
    assert kpis.stopped and kpis.summary() == row


def test_stop_after_step_counts_up_to_that_step(sim):
    r = robot(sim)
    r.add_action(MoveAction(path=Pose.from_xyz(5.0, 0.0, 0.1)))
    kpis = sim.kpis()
    kpis.stop_after_step(12)
    steps(sim, 12)
    r.clear_actions()  # what the end of a timed run does to its missions' actions
    steps(sim, 5)
    row = kpis.summary()
    assert kpis.stopped and row.steps == 12 and row.moving_time_total_s == 12 * DT
    assert (row.actions_failed, row.actions_cancelled) == (0, 0)


def test_stop_after_a_step_already_run_stops_at_once(sim):
    kpis = sim.kpis()
    steps(sim, 3)
    kpis.stop_after_step(2)
    steps(sim, 2)
    assert kpis.stopped and kpis.summary().steps == 3


def test_a_robot_named_after_it_joined_is_reported_by_its_name_now(sim):
    kept = robot(sim, name="r")
    gone = robot(sim, y=2.0)
    kpis = sim.kpis()
    kept.name = "picker0"  # as a mission that names its fleet does
    gone.name = "picker1"
    sim.remove_object(gone)
    gone.name = "renamed after it left"
    assert [r.robot for r in kpis.per_robot()] == ["picker0", "picker1"]


def test_no_robots_gives_zero_means(sim):
    kpis = sim.kpis()
    steps(sim, 3)
    row = kpis.summary()
    assert row.robot_count == 0 and row.distance_mean_m == 0.0 and row.idle_time_mean_s == 0.0
    assert row.throughput_per_hour == 0.0 and kpis.per_robot() == []


def test_rows_have_fixed_columns(sim):
    robot(sim)
    row = sim.kpis().summary()
    assert list(row.as_dict()) == FleetKpis.columns()
    assert list(sim.kpis().per_robot()[0].as_dict()) == RobotKpis.columns()


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_a_mission_error_counts_once(sim, backend):
    kpis = sim.kpis()

    async def child():
        await sim.sleep(1.0)
        raise ValueError("boom")

    async def main():
        async with sim.task_group() as tg:  # the error reaches main again, in a group
            tg.start_soon(child)

    with pytest.raises(ValueError, match="boom"):  # fa.run raises a lone error as itself
        fa.run(sim, main, backend=backend)
    assert kpis.summary().mission_errors == 1


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_each_failed_child_counts_once(sim, backend):
    kpis = sim.kpis()
    failed = []
    sim.events.on(SimEvents.MISSION_FAILED, lambda mission, **_: failed.append(mission))

    async def failing() -> None:
        await sim.sleep(1.0)
        raise ValueError("boom")

    async def failing_cleanup() -> None:
        try:
            await sim.sleep(5.0)
        finally:  # cancelled by the group when failing() fails, and fails again
            raise RuntimeError("cleanup failed")

    async def main():
        async with sim.task_group() as tg:
            tg.start_soon(failing)
            tg.start_soon(failing_cleanup)

    with pytest.raises(BaseExceptionGroup) as info:
        fa.run(sim, main, backend=backend)
    assert sorted(type(e).__name__ for e in info.value.exceptions) == [
        "RuntimeError",
        "ValueError",
    ]
    assert len(failed) == 3  # both children, then main with both errors in a group
    assert kpis.summary().mission_errors == 2


def test_the_collector_sees_events_first_and_lets_robots_go_last(sim):
    # Handlers registered before the collector, at the default priority: with equal priorities
    # they would run first; the collector's priorities put it around them.
    def on_spawned(agent, **_):
        sim.events.emit(SimEvents.TASK_COMPLETED, sim=sim, agent=agent, task="spawned")

    def on_removed(obj, **_):
        sim.events.emit(SimEvents.TASK_FAILED, sim=sim, agent=obj, task="removed")

    sim.events.on(SimEvents.AGENT_SPAWNED, on_spawned)
    sim.events.on(SimEvents.OBJECT_REMOVED, on_removed)
    kpis = sim.kpis()
    kpis.stop_after_step(3)

    def on_step(sim, step, **_):  # registered after stop_after_step: still counted at step 3
        if step == 3:
            sim.events.emit(SimEvents.TASK_COMPLETED, sim=sim, agent=None, task="last step")

    sim.events.on(SimEvents.POST_STEP, on_step)
    r = robot(sim, name="r0")  # joins before on_spawned reports its task
    steps(sim, 2)
    sim.remove_object(r)  # leaves after on_removed reported its task
    steps(sim, 3)
    row = kpis.summary()
    assert (row.tasks_completed, row.tasks_failed, row.steps) == (2, 1, 3)
    (detail,) = kpis.per_robot()
    assert (detail.tasks_completed, detail.tasks_failed) == (1, 1)


def test_devices_are_agents_but_not_robots(sim):
    door = fa.Door.from_dict({"name": "d", "pose": [5.0, 5.0, 0.0], "open_time": 0.5}, sim)
    r = robot(sim, name="r0")
    kpis = sim.kpis()
    door.request_open()  # the door's own action: not a fleet figure
    r.add_action(WaitAction(duration=1.0))
    steps(sim, 10)
    assert door.is_open and len(sim.agents) == 2
    row = kpis.summary()
    assert row.robot_count == 1 and [d.robot for d in kpis.per_robot()] == ["r0"]
    assert (row.actions_completed, row.waiting_time_total_s) == (1, 10 * DT)


def test_a_first_call_after_a_run_is_an_error_not_a_row_of_zeros(sim):
    r = robot(sim, name="r0")
    r.add_action(MoveAction(path=Pose.from_xyz(1.0, 0.0, 0.1)))
    steps(sim, 20)
    with pytest.raises(RuntimeError, match=r"first called after 20 steps \(2 s of sim time\)"):
        sim.kpis()
    kpis = sim.kpis(from_now=True)  # counting from here on is asked for
    steps(sim, 5)
    assert kpis.summary().steps == 5 and sim.kpis() is kpis


@pytest.fixture
def other_sim():
    core = fa.MultiRobotSimulationCore(
        fa.SimulationParams(gui=False, monitor=False, target_rtf=0.0, timestep=DT, seed=0)
    )
    yield core
    core.close()


def test_kpis_let_idle_steps_skip_and_a_skipped_span_counts_as_stepped(sim, other_sim):
    def scene(s):
        battery = [{"type": "battery", "config": {"drain_per_second": 0.001}}]
        a = robot(s, 0.0, 0.0, "a", plugins=battery)
        robot(s, 3.0, 0.0, "b", plugins=battery)
        a.add_action(WaitAction(duration=20.0))
        kpis = s.kpis()
        kpis.stop_after_step(250)
        a.set_goal_pose(Pose.from_xyz(1.0, 0.0, 0.1))
        for _ in range(30):  # drive, stop, then only a wait timer is pending
            s.step_once()
        return kpis

    stepped, skipped = scene(sim), scene(other_sim)
    for _ in range(270):
        sim.step_once()
    ran = 0
    while other_sim.step_count < 300:
        if not other_sim.skip_idle_steps(300 - other_sim.step_count):
            other_sim.step_once()
            ran += 1
    assert other_sim.step_count == 300 and ran < 10
    assert stepped.stopped and skipped.stopped
    assert stepped.summary() == skipped.summary()
    assert stepped.per_robot() == skipped.per_robot()
    assert stepped.summary().steps == 250
