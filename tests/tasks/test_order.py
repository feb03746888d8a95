"""The mission kernel's order rule and the bugs it fixed, each on both backends.

Every resumption of a mission is an event ordered by (step, class, sequence): URGENT (starts,
interrupts, cancel deliveries), then STEP (actions that ended during the step), then NORMAL
(everything else, by the sequence number taken when it was scheduled).
"""

from __future__ import annotations

import sys

import pytest

import fleet_async as fa
from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimulationParams

if sys.version_info < (3, 11):
    from exceptiongroup import BaseExceptionGroup

BACKENDS = ["asyncio", "trio"]


def _sim(dt: float = 0.1) -> MultiRobotSimulationCore:
    return MultiRobotSimulationCore(
        SimulationParams(gui=False, monitor=False, target_rtf=0.0, timestep=dt, enable_floor=False)
    )


def _robot(sim: MultiRobotSimulationCore, x: float = 0.0, y: float = 0.0) -> Agent:
    box = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
    return Agent.from_mesh(box, box, Pose.from_xyz(x, y, 0.1), sim_core=sim, controller="omni")


# ----- the reported bugs ---------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_cancelled_before_its_first_await_and_the_sim_runs_again(backend):
    with _sim() as sim:

        async def first_statement_times_out():
            with sim.move_on_after(0) as scope:
                await sim.sleep(1)
            return scope.cancelled_caught, sim.step_count

        assert fa.run(sim, first_statement_times_out, backend=backend) == (True, 0)

        async def body_raises_before_awaiting():
            async with sim.task_group() as tg:
                tg.start_soon(sim.sleep, 1.0)
                raise KeyError("early")

        with pytest.raises(KeyError, match="early"):
            fa.run(sim, body_raises_before_awaiting, backend=backend)

        async def started_then_cancelled():
            log = []

            async def child():
                log.append("started")
                await sim.sleep(1.0)
                log.append("not reached")

            async with sim.task_group() as tg:
                handle = tg.start_soon(child)
                tg.cancel_scope.cancel()
            return log, handle.cancelled

        assert fa.run(sim, started_then_cancelled, backend=backend) == (["started"], True)

        async def winner_returns_without_waiting():
            async def instant():
                return "now"

            return await sim.race(instant, sim.sleep(5.0))

        assert fa.run(sim, winner_returns_without_waiting, backend=backend) == (0, "now")

        async def gather_a_number():
            await sim.gather(42)

        with pytest.raises(TypeError, match="42"):
            fa.run(sim, gather_a_number, backend=backend)

        async def still_works():
            await sim.sleep(0.5)
            return sim.step_count

        start = sim.step_count
        assert fa.run(sim, still_works, backend=backend) == start + 5


@pytest.mark.parametrize("backend", BACKENDS)
def test_interrupt_in_the_step_of_the_victims_own_wake_loses_nothing(backend):
    with _sim(dt=1.0) as sim:
        log = []

        async def victim():
            try:
                await sim.sleep(1)  # due at t=1, like the interrupter's wake
            except fa.Interrupt as interrupt:
                log.append((sim.now, "interrupted", interrupt.cause))
            await sim.sleep(1)
            log.append((sim.now, "woke"))

        async def main():
            async with sim.task_group() as tg:
                target = tg.start_soon(victim)
                await sim.sleep(1)  # scheduled before the victim's own sleep: resumes first
                target.interrupt("now")

        fa.run(sim, main, backend=backend, watchdog=5.0)
        assert log == [(1.0, "interrupted", "now"), (2.0, "woke")]


@pytest.mark.parametrize("backend", BACKENDS)
def test_holder_and_waiter_timeouts_in_the_same_step_keep_the_slot(backend):
    with _sim(dt=1.0) as sim:
        lock = fa.Resource(sim, capacity=1)
        log = []

        async def holder():
            with sim.move_on_after(2):
                async with lock.request():
                    await sim.sleep(10)
            log.append((sim.now, "holder out"))

        async def waiter():
            await sim.sleep(1)
            with sim.move_on_after(1):  # fires at t=2, with the holder's
                async with lock.request():
                    log.append((sim.now, "waiter in"))
                    await sim.sleep(5)
            log.append((sim.now, "waiter out"))

        async def latecomer():
            await sim.sleep(3)
            async with lock.request():
                log.append((sim.now, "latecomer in"))

        async def main():
            async with sim.task_group() as tg:
                tg.start_soon(holder)
                tg.start_soon(waiter)
                tg.start_soon(latecomer)

        fa.run(sim, main, backend=backend)
        assert log == [(2.0, "holder out"), (2.0, "waiter out"), (3.0, "latecomer in")]
        assert lock.count == 0
        assert lock.queued == 0


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_lone_mission_error_is_raised_as_itself(backend):
    with _sim() as sim:

        async def main():
            await sim.sleep(0.2)
            raise ValueError("main failed")

        with pytest.raises(ValueError, match="main failed") as caught:
            fa.run(sim, main, backend=backend)
        assert "in mission 'main' at sim time 0.200 s" in getattr(caught.value, "__notes__", [""])

        async def child():
            await sim.sleep(0.3)
            raise ValueError("child failed")

        async def parent():
            async with sim.task_group() as tg:
                tg.start_soon(child, name="child")

        with pytest.raises(ValueError, match="child failed") as caught:
            fa.run(sim, parent, backend=backend)
        assert getattr(caught.value, "__notes__", []) == ["in mission 'child' at sim time 0.500 s"]

        async def body_fails():  # the task group's own body raises: the group fails the mission
            async with sim.task_group():
                await sim.sleep(0.1)
                raise KeyError("body")

        with pytest.raises(KeyError) as caught_key:
            fa.run(sim, body_fails, backend=backend)
        assert getattr(caught_key.value, "__notes__", []) == [
            "in mission 'body_fails' at sim time 0.600 s"
        ]


@pytest.mark.parametrize("backend", BACKENDS)
def test_concurrent_errors_come_as_one_exception_group(backend):
    with _sim() as sim:

        async def fail():
            await sim.sleep(0.1)
            raise ValueError(1)

        async def fail_while_cancelled():
            try:
                await sim.sleep(1.0)
            finally:
                raise ValueError(2)  # its cleanup fails too, at the same sim time

        async def main():
            async with sim.task_group() as tg:
                tg.start_soon(fail)
                tg.start_soon(fail_while_cancelled)

        with pytest.raises(BaseExceptionGroup) as caught:
            fa.run(sim, main, backend=backend)
        assert [e.args[0] for e in caught.value.exceptions] == [1, 2]


# ----- one order, whatever the backend and the run ------------------------------------------


def _order_program(sim: MultiRobotSimulationCore, log: list) -> object:
    """Cancellations, a parent's except*, gather joins, sleep(0), an Event, a Resource."""
    flag = fa.Event(sim)
    pool = fa.Resource(sim, capacity=1)

    async def worker(name, delay):
        try:
            await sim.sleep(delay)
            log.append((sim.now, name, "slept"))
            await sim.sleep(0)
            log.append((sim.now, name, "yielded"))
            async with pool.request():
                log.append((sim.now, name, "holds"))
                await flag
                log.append((sim.now, name, "flag"))
            if name == "w2":
                raise ValueError(name)
        except fa.Cancelled:
            log.append((sim.now, name, "cancelled"))
            raise

    async def setter():
        await sim.sleep(0.3)
        flag.set()
        log.append((sim.now, "setter", "set"))

    async def main():
        results = await sim.gather(sim.timeout(0.1, "a"), sim.timeout(0.1, "b"))
        log.append((sim.now, "main", tuple(results)))
        try:
            async with sim.task_group() as tg:
                for i in range(4):
                    tg.start_soon(worker, f"w{i}", 0.1 * (i % 2))
                tg.start_soon(setter)
        except BaseExceptionGroup as group:  # except* on Python >= 3.11
            matched, rest = group.split(ValueError)
            assert rest is None
            log.append((sim.now, "main", "except*", len(matched.exceptions)))
        return "done"

    return main


def _order_trace(backend: str) -> list:
    with _sim() as sim:
        log: list = []
        assert fa.run(sim, _order_program(sim, log), backend=backend) == "done"
        return log


def test_one_order_on_both_backends_run_after_run():
    reference = _order_trace("asyncio")
    assert ("cancelled" in str(reference)) and ("except*" in str(reference))
    for _ in range(4):  # trio shuffles its run queue: several runs
        assert _order_trace("trio") == reference
    assert _order_trace("asyncio") == reference


# ----- the tie policy: an action ending in its timeout's step counts as completed -------------


async def test_an_action_ending_in_the_step_of_its_timeout_completes(fleet_sim):
    robot = _robot(fleet_sim)
    with fleet_sim.move_on_after(1.0) as scope:
        done = await robot.wait(1.0)  # ends at exactly t + 1.0, in the step the scope fires
    assert not scope.cancelled_caught
    assert done.status is fa.ActionStatus.COMPLETED
    assert fleet_sim.step_count == 10
    index, _ = await fleet_sim.race(fleet_sim.sleep(1.0), robot.wait(1.0))
    assert index == 1  # the action's outcome comes before the timer due at the same step
    assert fleet_sim.step_count == 20


# ----- interrupts -----------------------------------------------------------------------------


async def test_interrupting_a_mission_that_awaits_an_action_stops_the_robot(fleet_sim):
    robot = _robot(fleet_sim)
    log = []

    async def courier():
        try:
            await robot.move(Pose.from_xyz(10, 0, 0.1))
        except fa.Interrupt as interrupt:
            log.append((fleet_sim.step_count, "interrupted", interrupt.cause))
            assert not robot.is_moving
            x_when_stopped = robot.get_pose().x
            await fleet_sim.sleep(0.5)
            assert robot.get_pose().x == x_when_stopped  # it stayed where it stopped
        await robot.move(Pose.from_xyz(0, 0, 0.1))
        log.append((fleet_sim.step_count, "home"))

    async with fleet_sim.task_group() as tg:
        mission = tg.start_soon(courier)
        await fleet_sim.sleep(1.0)
        mission.interrupt("reroute")
    assert log[0] == (10, "interrupted", "reroute")
    assert log[1][1] == "home"
    assert robot.get_pose().x == pytest.approx(0.0)


async def test_interrupt_errors(fleet_sim):
    async def quick():
        return 1

    async with fleet_sim.task_group() as tg:
        done = tg.start_soon(quick)
    with pytest.raises(RuntimeError, match="has ended"):
        done.interrupt()
    with pytest.raises(RuntimeError, match="cannot interrupt itself"):
        fleet_sim.active_mission.interrupt()


# ----- run(until=...) -------------------------------------------------------------------------


def _ticker(sim, log):
    """A mission that logs a tick every sim second and its cleanup."""

    async def ticker():
        try:
            while True:
                await sim.sleep(1)
                log.append((sim.now, "tick"))
        finally:
            log.append((sim.now, "cleanup"))

    return ticker


@pytest.mark.parametrize("backend", BACKENDS)
def test_until_stops_before_the_events_due_then_and_cleanup_runs_then(backend):
    with _sim(dt=1.0) as sim:
        log = []
        ticker = _ticker(sim, log)
        assert fa.run(sim, ticker, until=3.0, then="cancel", backend=backend) is None
        assert log == [(1.0, "tick"), (2.0, "tick"), (3.0, "cleanup")]
        assert sim.sim_time == 3.0
        assert sim.suspended_missions() == []


@pytest.mark.parametrize("backend", BACKENDS)
def test_until_suspends_and_the_next_run_continues_the_same_missions(backend):
    """SimPy's run(until=t): the missions stay where they wait; run(until=t2) goes on."""
    with _sim(dt=1.0) as sim:
        log = []
        ticker = _ticker(sim, log)
        assert fa.run(sim, ticker, until=3.0, backend=backend) is None
        assert log == [(1.0, "tick"), (2.0, "tick")]  # the tick due at 3.0 waits for the next
        assert sim.sim_time == 3.0 and sim.suspended_missions() == ["ticker"]
        assert fa.run(sim, until=5.0, backend=backend) is None
        assert log[2:] == [(3.0, "tick"), (4.0, "tick")]
        sim.end_missions()
        assert log[-1] == (5.0, "cleanup") and sim.suspended_missions() == []


@pytest.mark.parametrize("backend", BACKENDS)
def test_until_is_not_a_deadlock(backend):
    """A model whose processes end up waiting forever (SimPy style) just stops at ``until``."""
    with _sim(dt=1.0) as sim:
        store = fa.Store(sim)

        async def consumer():
            while True:
                await store.get()

        assert fa.run(sim, consumer, until=5.0, backend=backend) is None
        assert sim.sim_time == 5.0
        with pytest.raises(fa.MissionDeadlockError, match="consumer"):
            fa.run(sim, consumer, backend=backend)


# ----- handles, events, conditions ---------------------------------------------------------


async def test_mission_handles(fleet_sim):
    async def worker(n):
        await fleet_sim.sleep(n)
        return n * 10

    async with fleet_sim.task_group() as tg:
        a = tg.start_soon(worker, 0.2)
        b = tg.start_soon(worker, 5.0)
        assert a.is_alive
        assert await a == 2.0
        assert fleet_sim.now == pytest.approx(0.2)
        with pytest.raises(RuntimeError, match="still running"):
            b.result()
        b.cancel()
        with pytest.raises(fa.MissionCancelledError):
            await b.join()
    assert a.result() == 2.0 and not a.is_alive
    assert b.cancelled and not b.is_alive
    assert fleet_sim.now == pytest.approx(0.2)

    background = fleet_sim.spawn(worker, 0.1, name="background")
    assert background.name == "background"
    assert await background == 1.0


async def test_event_values_failures_and_conditions(fleet_sim):
    ev = fa.Event(fleet_sim)
    fleet_sim.spawn(_set_later, fleet_sim, ev, 0.3, "payload")
    assert await ev == "payload"
    assert ev.is_set() and ev.value == "payload" and ev.processed

    broken = fleet_sim.event()
    broken.fail(KeyError("nope"))
    with pytest.raises(KeyError):
        await broken

    slow, fast = fleet_sim.timeout(0.5, "slow"), fleet_sim.timeout(0.2, "fast")
    first = await fleet_sim.any_of(slow, fast)
    assert first == {fast: "fast"} and fleet_sim.now == pytest.approx(0.5)
    both = await (slow & fast)
    assert both == {slow: "slow", fast: "fast"} and fleet_sim.now == pytest.approx(0.8)
    assert await fleet_sim.all_of([]) == {}


async def _set_later(sim, event, delay, value):
    await sim.sleep(delay)
    event.succeed(value)


async def test_sleep_rejects_negative_and_sleep_zero_yields(fleet_sim):
    with pytest.raises(ValueError, match=r"sim\.sleep.*-1"):
        fleet_sim.sleep(-1)
    log = []

    async def other():
        log.append("other ran")

    fleet_sim.spawn(other)
    await fleet_sim.sleep(0)  # yields: the mission started now runs first
    assert log == ["other ran"] and fleet_sim.step_count == 0


# ----- resources, containers, stores ---------------------------------------------------------


async def test_preemption_interrupts_the_least_important_holder(fleet_sim):
    crane = fa.PreemptiveResource(fleet_sim, capacity=1)
    log = []

    async def user(name, priority, start, hold):
        await fleet_sim.sleep(start)
        with crane.request(priority=priority) as req:
            await req
            log.append((round(fleet_sim.now, 3), name, "got"))
            try:
                await fleet_sim.sleep(hold)
                log.append((round(fleet_sim.now, 3), name, "done"))
            except fa.Interrupt as interrupt:
                cause = interrupt.cause
                assert isinstance(cause, fa.Preempted) and cause.resource is crane
                log.append((round(fleet_sim.now, 3), name, "preempted", cause.usage_since))

    async with fleet_sim.task_group() as tg:
        tg.start_soon(user, "low", 5, 0.0, 1.0)
        tg.start_soon(user, "high", 1, 0.3, 0.2)
    assert log == [
        (0.0, "low", "got"),
        (0.3, "low", "preempted", 0.0),  # the interrupt is URGENT; the grant is NORMAL
        (0.3, "high", "got"),
        (0.5, "high", "done"),
    ]


async def test_container_levels(fleet_sim):
    tank = fa.Container(fleet_sim, capacity=10, init=2)
    log = []

    async def consumer():
        await tank.get(5)
        log.append((round(fleet_sim.now, 3), tank.level))

    async with fleet_sim.task_group() as tg:
        tg.start_soon(consumer)
        await fleet_sim.sleep(0.4)
        await tank.put(4)
    assert log == [(0.4, 1)]
    with pytest.raises(ValueError, match="amount must be > 0"):
        tank.put(0)
    with pytest.raises(ValueError, match="init"):
        fa.Container(fleet_sim, capacity=1, init=2)


async def test_request_composes_with_a_timeout(fleet_sim):
    desk = fa.Resource(fleet_sim, capacity=1)
    log = []

    async def customer(name, patience):
        with desk.request() as req:
            got = await (req | fleet_sim.timeout(patience))
            if req in got:
                log.append((round(fleet_sim.now, 3), name, "served"))
                await fleet_sim.sleep(1.0)
            else:
                log.append((round(fleet_sim.now, 3), name, "reneged"))

    async with fleet_sim.task_group() as tg:
        tg.start_soon(customer, "a", 5.0)
        tg.start_soon(customer, "b", 0.5)
        tg.start_soon(customer, "c", 2.0)
    assert log == [(0.0, "a", "served"), (0.5, "b", "reneged"), (1.0, "c", "served")]
    assert desk.count == 0 and desk.queued == 0


async def test_store_filters_and_priorities(fleet_sim):
    shelf = fa.Store(fleet_sim, capacity=2)
    await shelf.put("bolt")
    await shelf.put("nut")
    blocked = fleet_sim.spawn(_put, shelf, "washer")
    await fleet_sim.sleep(0.1)
    assert blocked.is_alive and shelf.items == ["bolt", "nut"]
    assert await shelf.get(lambda item: item == "nut") == "nut"
    await blocked
    assert shelf.items == ["bolt", "washer"]

    ranked = fa.PriorityStore(fleet_sim)
    for priority, item in [(3, "c"), (1, "a"), (2, "b")]:
        await ranked.put(fa.PriorityItem(priority, item))
    assert [(await ranked.get()).item for _ in range(3)] == ["a", "b", "c"]


async def _put(store, item):
    await store.put(item)


def test_primitives_are_importable_from_the_package():
    for name in [
        "Event",
        "Resource",
        "PriorityResource",
        "PreemptiveResource",
        "Preempted",
        "Lock",
        "Container",
        "Store",
        "FilterStore",
        "PriorityStore",
        "PriorityItem",
        "Interrupt",
        "Cancelled",
        "Mission",
        "CancelScope",
    ]:
        assert name in fa.__all__ and getattr(fa, name) is not None


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_failed_mission_is_announced_on_the_bus(backend):
    with _sim() as sim:
        seen = []
        sim.events.on(
            fa.SimEvents.MISSION_FAILED,
            lambda sim, mission, error: seen.append((sim.step_count, mission, str(error))),
        )

        async def doomed():
            await sim.sleep(0.2)
            raise KeyError("lost pallet")

        async def main():
            async with sim.task_group() as tg:
                tg.start_soon(doomed, name="doomed")
                tg.start_soon(sim.sleep, 5.0)  # cancelled: not a failure

        with pytest.raises(KeyError):
            fa.run(sim, main, backend=backend)
        assert seen == [
            (2, "doomed", "'lost pallet'"),
            (2, "main", "errors in a sim task group (1 sub-exception)"),  # it fails too
        ]


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_store_serves_one_waiting_get_per_turn_as_simpy(backend):
    """Two getters wait; two items arrive in one step: the second getter is served when the
    second put is processed, after what the producer scheduled in between (SimPy's Store)."""
    import simpy

    def simpy_log():
        env, log = simpy.Environment(), []
        store = simpy.Store(env)

        def getter(name):
            log.append((env.now, name, (yield store.get())))

        def producer():
            yield env.timeout(1)
            put = store.put("a")
            store.put("b")
            yield put
            yield env.timeout(0)
            log.append((env.now, "producer", "after timeout(0)"))

        for process in (getter("g1"), getter("g2"), producer()):
            env.process(process)
        env.run()
        return log

    with _sim(dt=1.0) as sim:
        log = []
        store = fa.Store(sim)

        async def getter(name):
            log.append((sim.now, name, await store.get()))

        async def producer():
            await sim.timeout(1)
            put = store.put("a")
            store.put("b")
            await put
            await sim.timeout(0)
            log.append((sim.now, "producer", "after timeout(0)"))

        async def main():
            for mission in (getter("g1"), getter("g2"), producer()):
                sim.spawn(mission)

        fa.run(sim, main, backend=backend)
        assert log == simpy_log()


async def test_two_missions_can_wait_on_one_action(fleet_sim):
    robot = _robot(fleet_sim)
    first = robot.wait(1.0)
    second = fleet_sim.mission_runtime.wait_action(robot, first.action)
    assert second is first
    ended = []

    async def watcher():
        await second
        ended.append(fleet_sim.step_count)

    watching = fleet_sim.spawn(watcher)
    await first
    await watching
    assert ended == [10] and fleet_sim.step_count == 10


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_driver_jumps_over_empty_steps_exactly(backend):
    """Missions that wait on timers while nothing moves: the driver skips the empty steps in
    one go, and everything happens at the same sim times as when every step runs."""

    def trace(keep_every_step: bool) -> tuple[list, int, int]:
        with _sim(dt=0.5) as sim:
            robot = _robot(sim)
            log, skipped = [], []
            if keep_every_step:  # a per-step subscriber: no step may be skipped
                sim.events.on(fa.SimEvents.POST_STEP, lambda **_: None)
            sim.events.on(fa.SimEvents.STEPS_SKIPPED, lambda count, **_: skipped.append(count))
            sim.register_callback(lambda sim, dt: log.append(("tick", sim.step_count)), 0.1)

            async def sleeper(name, period):
                for _ in range(4):
                    await sim.sleep(period)
                    log.append((name, sim.step_count))

            async def mover():
                await sim.sleep(7)
                await robot.move(Pose.from_xyz(2, 0, 0.1))
                log.append(("moved", sim.step_count, round(robot.get_pose().x, 6)))

            async def main():
                async with sim.task_group() as tg:
                    tg.start_soon(sleeper, "a", 3.0)
                    tg.start_soon(sleeper, "b", 5.5)
                    tg.start_soon(mover)

            fa.run(sim, main, backend=backend)
            return log, sim.step_count, sum(skipped)

    skipping, steps, skipped = trace(keep_every_step=False)
    every_step, steps_again, none = trace(keep_every_step=True)
    assert skipping == every_step and steps == steps_again == 44
    assert skipped > 20 and none == 0
