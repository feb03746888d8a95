"""Missions behave as SimPy's processes do where a SimPy user relies on it (issue 25), and runs
always end (issue 27): each case on both backends.

- things made before a run start when it starts; ``run(until=t)`` suspends and the next run
  continues; ``until`` in the past is an error; ``until=event``; deadlocks raise or return;
- a failed event nobody waits on fails the run; each waiter gets its own copy of a failure;
- an interrupt leaves a request queued; nothing is lost or made twice; preemption order;
- a mission's actions end with it unless detached;
- anyio's own primitives in missions are clear errors; a mission that swallows its
  cancellation, waits on a predicate nothing can change, or loops in Python never hangs a run.
"""

from __future__ import annotations

import contextlib
import logging

import anyio
import pytest

import fleet_async as fa
from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimulationParams

BACKENDS = ["asyncio", "trio"]


def _sim(dt: float = 1.0) -> MultiRobotSimulationCore:
    return MultiRobotSimulationCore(
        SimulationParams(gui=False, monitor=False, target_rtf=0.0, timestep=dt, enable_floor=False)
    )


def _robot(sim: MultiRobotSimulationCore) -> Agent:
    box = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
    return Agent.from_mesh(box, box, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")


# ----- building before a run, and how runs end -----------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_timers_conditions_requests_and_missions_made_before_a_run_start_with_it(backend):
    with _sim() as sim:
        log = []
        timer = sim.timeout(2, "two")
        nothing = sim.any_of([])
        slot = fa.Resource(sim, capacity=1)
        request = slot.request()

        async def waiter():
            value = await timer
            log.append((sim.now, value))
            value = await nothing
            log.append((sim.now, value))

        async def user():
            await request
            log.append((sim.now, "granted"))
            await slot.release(request)

        sim.spawn(waiter, name="waiter")
        assert fa.run(sim, user, backend=backend) is None
        assert log == [(0.0, "granted"), (2.0, "two"), (2.0, {})]
        assert slot.count == 0


@pytest.mark.parametrize("backend", BACKENDS)
def test_until_now_or_earlier_is_an_error_and_an_empty_run_still_reaches_until(backend):
    with _sim() as sim:
        assert fa.run(sim, until=4.0, backend=backend) is None
        assert sim.sim_time == 4.0  # SimPy: the clock reaches until though nothing happens
        for bad in (4.0, 1.0):
            with pytest.raises(ValueError, match=r"until=.* must be later than the current"):
                fa.run(sim, until=bad, backend=backend)
        with pytest.raises(ValueError, match="then must be"):
            fa.run(sim, until=5.0, then="stop", backend=backend)


@pytest.mark.parametrize("backend", BACKENDS)
def test_until_an_event_returns_its_value_and_one_that_cannot_come_is_a_deadlock(backend):
    with _sim() as sim:

        async def worker():
            await sim.sleep(3)
            return "done"

        assert fa.run(sim, until=sim.spawn(worker), backend=backend) == "done"
        assert sim.sim_time == 3.0
        never = fa.Event(sim)
        with pytest.raises(fa.MissionDeadlockError, match="can no longer come"):
            fa.run(sim, until=never, backend=backend)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_deadlock_raises_by_default_and_returns_on_request(backend):
    with _sim() as sim:
        store = fa.Store(sim)
        got = []

        async def consumer():
            while True:
                got.append(await store.get())

        assert fa.run(sim, consumer, on_deadlock="return", backend=backend) is None
        assert sim.suspended_missions() == ["consumer"]
        store.put("part")  # from outside, between runs: served when the next run starts
        with pytest.raises(fa.MissionDeadlockError, match="consumer on <StoreGet"):
            fa.run(sim, backend=backend)
        assert got == ["part"] and sim.suspended_missions() == []


@pytest.mark.parametrize("backend", BACKENDS)
def test_suspended_missions_cannot_be_checkpointed(backend, tmp_path):
    with _sim() as sim:

        async def sleeper():
            await sim.sleep(10)

        fa.run(sim, sleeper, until=2.0, backend=backend)
        with pytest.raises(fa.CheckpointError, match=r"missions \['sleeper'\] wait mid-await"):
            sim.save_state(tmp_path / "mid.ckpt")
        sim.end_missions()
        sim.save_state(tmp_path / "mid.ckpt")


@pytest.mark.parametrize("backend", BACKENDS)
def test_closing_the_simulation_ends_its_suspended_missions(backend):
    sim = _sim()
    log = []

    async def sleeper():
        try:
            await sim.sleep(10)
        finally:
            log.append(sim.now)

    fa.run(sim, sleeper, until=2.0, backend=backend)
    assert log == []
    sim.close()
    assert log == [2.0]


# ----- failures ---------------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_failed_event_nobody_waits_on_fails_the_run_unless_defused(backend):
    with _sim() as sim:
        lost = fa.Event(sim)  # the line the message names

        async def main():
            await sim.sleep(1)
            lost.fail(KeyError("nobody listens"))
            await sim.sleep(5)

        with pytest.raises(KeyError, match="nobody listens") as info:
            fa.run(sim, main, backend=backend)
        notes = "\n".join(getattr(info.value, "__notes__", []))
        assert f"made at {__file__}:" in notes and "failed at sim time 1.000 s" in notes
        assert sim.sim_time == 1.0

        defused = fa.Event(sim)

        async def careful():
            defused.fail(KeyError("expected"))
            defused.defused = True
            await sim.sleep(2)

        fa.run(sim, careful, backend=backend)
        assert sim.sim_time == 3.0


@pytest.mark.parametrize("backend", BACKENDS)
def test_each_waiter_gets_its_own_copy_of_a_failure_chained_to_the_original(backend):
    with _sim() as sim:
        alarm = fa.Event(sim)
        caught = []

        async def waiter():
            try:
                await alarm
            except KeyError as error:
                caught.append(error)

        async def main():
            async with sim.task_group() as tg:
                tg.start_soon(waiter)
                tg.start_soon(waiter)
                await sim.sleep(1)
                alarm.fail(KeyError("fire"))

        fa.run(sim, main, backend=backend)
        first, second = caught
        assert first is not second and first.args == second.args == ("fire",)
        assert first.__cause__ is second.__cause__ is alarm.value


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("until", [None, 2.0, 20.0])
def test_a_run_fails_at_the_time_of_the_failure_whatever_until(backend, until):
    """The failure's time, not ``until``, ends the run: a cut run and an uncut one agree."""
    with _sim() as sim:
        log = []

        async def careful():
            try:
                await sim.sleep(100)
            finally:
                with sim.cancel_scope(shield=True):
                    log.append(("cleanup", sim.now))
                    await sim.sleep(5)  # would outlast the failure: closed instead
                    log.append(("parked", sim.now))

        async def failing():
            await sim.sleep(1)
            raise KeyError("broken")

        async def main():
            sim.spawn(careful)
            sim.spawn(failing)

        with pytest.raises(KeyError, match="broken"):
            fa.run(sim, main, until=until, backend=backend)
        assert log == [("cleanup", 1.0)] and sim.sim_time == 1.0
        assert sim.suspended_missions() == []


# ----- requests: interrupts, conservation, preemption ------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_an_interrupt_leaves_a_queued_request_queued(backend):
    with _sim() as sim:
        slot = fa.Resource(sim, capacity=1)
        log = []

        async def holder():
            async with slot.request():
                await sim.sleep(5)

        async def waiter():
            with slot.request() as request:
                try:
                    await request
                except fa.Interrupt:
                    log.append((sim.now, "interrupted", len(slot.queue)))
                    await request  # SimPy: still queued, granted in its turn
                log.append((sim.now, "granted"))

        async def main():
            sim.spawn(holder)
            victim = sim.spawn(waiter)
            await sim.sleep(1)
            victim.interrupt("hurry")

        fa.run(sim, main, backend=backend)
        assert log == [(1.0, "interrupted", 1), (5.0, "granted")]
        assert slot.count == 0 and not slot.queue


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(
    ("how", "again"), [("interrupt", True), ("interrupt", False), ("cancel", False)]
)
def test_a_get_served_but_given_up_hands_its_item_over_exactly_once(backend, how, again):
    with _sim() as sim:
        store = fa.Store(sim)
        tank = fa.Container(sim, capacity=10, init=0)
        got = []

        async def getter():
            with store.get() as item, tank.get(3) as amount:
                try:
                    await (item & amount)
                except fa.Interrupt:
                    if again:
                        got.append(await item)
                        await amount
                        got.append(3)

        async def main():
            victim = sim.spawn(getter)
            await sim.sleep(1)
            store.put("tote")  # serves the get at once; its waiter resumes later in the step
            tank.put(3)
            await sim.sleep(0)
            # ... but the interrupt or the cancellation comes first (URGENT)
            victim.interrupt("now") if how == "interrupt" else victim.cancel()
            await sim.sleep(1)

        fa.run(sim, main, backend=backend)
        if again:
            assert got == ["tote", 3] and store.items == [] and tank.level == 0
        else:  # given up without taking them: both went back, nothing twice
            assert got == [] and store.items == ["tote"] and tank.level == 3


@pytest.mark.parametrize("backend", BACKENDS)
def test_preemption_among_equal_holders_takes_the_slot_granted_last(backend):
    with _sim() as sim:
        slots = fa.PreemptiveResource(sim, capacity=2)
        preempted = []

        async def user(name, priority, start):
            await sim.sleep(start)
            with slots.request(priority=priority) as request:
                try:
                    await request
                    await sim.sleep(10)
                except fa.Interrupt as interrupt:
                    preempted.append((name, sim.now, interrupt.cause.usage_since))

        async def main():
            async with sim.task_group() as tg:
                tg.start_soon(user, "first", 0, 0)
                tg.start_soon(user, "second", 0, 0)
                tg.start_soon(user, "urgent", -1, 1)

        fa.run(sim, main, backend=backend)
        assert preempted == [("second", 1.0, 0.0)]


# ----- actions belong to their mission ------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_missions_unfinished_actions_stop_when_it_ends_unless_detached(backend):
    with _sim(dt=0.1) as sim:
        robot = _robot(sim)

        async def forgetful():
            robot.move(Pose.from_xyz(20, 0, 0.1))  # not awaited
            await sim.sleep(1)

        fa.run(sim, forgetful, backend=backend)
        assert robot.get_current_action() is None and not robot.is_moving
        stopped_at = robot.get_pose().x
        sim.step_once()
        assert robot.get_pose().x == stopped_at

        async def errand():
            robot.move(Pose.from_xyz(0, 0, 0.1), detached=True)
            await sim.sleep(0.5)

        fa.run(sim, errand, backend=backend)
        assert robot.is_moving  # it drives on after its mission ended
        for _ in range(200):
            sim.step_once()
        assert robot.get_pose().x == pytest.approx(0.0, abs=1e-6)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_detached_actions_failure_is_logged_and_fails_nothing(backend, caplog):
    with _sim(dt=0.1) as sim:
        robot = _robot(sim)

        async def main():
            robot.pick(target_position=[50.0, 50.0, 0.0], search_radius=0.1, detached=True)
            await sim.sleep(2)

        with caplog.at_level(logging.WARNING, logger="fleet_async.tasks.waits"):
            fa.run(sim, main, backend=backend)
        failures = [r.getMessage() for r in caplog.records if "detached" in r.getMessage()]
        assert len(failures) == 1, caplog.text
        assert failures[0].startswith(f"detached agent.pick of {robot.name!r} failed: PickAction")


# ----- anyio's own primitives in missions ----------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_an_anyio_task_group_starting_a_sim_wait_says_to_start_a_mission(backend):
    with _sim() as sim:

        async def main():
            async with anyio.create_task_group() as tg:
                tg.start_soon(sim.sleep, 1.0)

        with pytest.raises(BaseException, match=r"anyio.create_task_group\(\).*sim.task_group"):
            fa.run(sim, main, backend=backend, watchdog=5.0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_an_anyio_cancel_scope_cancelled_from_another_mission_is_a_clear_error(backend):
    with _sim() as sim:
        scopes = []

        async def target():
            with anyio.CancelScope() as scope:
                scopes.append(scope)
                await sim.sleep(5)

        async def canceller():
            await sim.sleep(1)
            scopes[0].cancel()

        async def main():
            async with sim.task_group() as tg:
                tg.start_soon(target)
                tg.start_soon(canceller)

        with pytest.raises(fa.NoMissionRuntimeError, match=r"anyio cancel scope.*sim.cancel_scope"):
            fa.run(sim, main, backend=backend)
        assert sim.sim_time == 1.0


# ----- runs that always end (issue 27) ------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_mission_that_swallows_its_cancellation_is_ended_with_a_clear_error(backend):
    with _sim() as sim:

        async def stubborn():
            while True:
                with contextlib.suppress(fa.Cancelled):  # wrong: it keeps going
                    await sim.sleep(1)

        with pytest.raises(RuntimeError, match="caught its cancellation and awaited sim time"):
            fa.run(sim, stubborn, until=3.0, then="cancel", backend=backend)


@pytest.mark.parametrize("backend", BACKENDS)
def test_waiting_on_a_predicate_nothing_can_change_is_a_deadlock(backend):
    with _sim() as sim:

        async def hopeful():
            await sim.wait_until(lambda: False)

        with pytest.raises(fa.MissionDeadlockError, match=r"wait_until predicates.*: hopeful on"):
            fa.run(sim, hopeful, backend=backend)
        assert sim.sim_time == 3600.0


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_mission_looping_in_python_is_named_with_its_line(backend):
    with _sim() as sim:

        async def spinner():
            n = 0
            while n >= 0:
                n += 1  # never awaits: the line the watchdog names

        with pytest.raises(fa.MissionStalledError) as info:
            fa.run(sim, spinner, backend=backend, watchdog=0.5)
        message = str(info.value)
        assert "mission 'spinner'" in message and "running Python code without awaiting" in message
        assert f"{__file__}:" in message and "in spinner" in message


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_missions_generator_follows_a_reseed(backend):
    def draw(seed, reseed=None):
        with MultiRobotSimulationCore(
            SimulationParams(gui=False, monitor=False, target_rtf=0.0, seed=seed)
        ) as sim:
            if reseed is not None:
                sim.reseed(reseed)

            async def main():
                return sim.mission_rng().random(3).tolist()

            return fa.run(sim, main, backend=backend)

    assert draw(0, reseed=7) == draw(7) != draw(0)
