"""Missions that stop waiting, runs that stop early, and misuse: nothing is lost or left
behind, and errors say what happened. Each case was found by a review of the kernel."""

from __future__ import annotations

import asyncio
import contextlib
import importlib.util
import itertools
import sys
import threading

import anyio
import pytest
import simpy

import fleet_async as fa
from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimulationParams

if sys.version_info < (3, 11):
    from exceptiongroup import BaseExceptionGroup

BACKENDS = ["asyncio", "trio"]


def _sim(dt: float = 1.0, rtf: float = 0.0) -> MultiRobotSimulationCore:
    return MultiRobotSimulationCore(
        SimulationParams(gui=False, monitor=False, target_rtf=rtf, timestep=dt, enable_floor=False)
    )


def _robot(sim: MultiRobotSimulationCore) -> Agent:
    box = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
    return Agent.from_mesh(box, box, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")


# ----- actions and conditions -------------------------------------------------------------


async def test_cancelling_a_queued_action_wakes_whoever_awaits_it(fleet_sim):
    robot = _robot(fleet_sim)
    robot.wait(1.0)
    queued = robot.wait(1.0)  # behind the first
    queued.cancel()
    with pytest.raises(fa.ActionCancelledError):
        await queued
    assert fleet_sim.step_count == 0


async def test_an_action_abandoned_by_an_interrupt_can_be_awaited_again(fleet_sim):
    robot = _robot(fleet_sim)
    move = robot.move(Pose.from_xyz(10, 0, 0.1))

    async def worker():
        with contextlib.suppress(fa.Interrupt):
            await move
        with pytest.raises(fa.ActionCancelledError):
            await move  # it was cancelled when the worker stopped waiting
        return "ok"

    mission = fleet_sim.spawn(worker)
    await fleet_sim.sleep(0.3)
    mission.interrupt()
    assert await mission == "ok"


async def test_a_cancelled_any_of_withdraws_its_requests_and_stops_its_robot(fleet_sim):
    robot = _robot(fleet_sim)
    store = fa.Store(fleet_sim)

    async def wait_for_a_part():
        await (store.get() | fleet_sim.timeout(100))

    async def drive_away():
        await fleet_sim.any_of(robot.move(Pose.from_xyz(50, 0, 0.1)), fleet_sim.timeout(100))

    async with fleet_sim.task_group() as tg:
        tg.start_soon(wait_for_a_part)
        tg.start_soon(drive_away)
        await fleet_sim.sleep(0.5)
        tg.cancel_scope.cancel()
    assert not store.get_queue
    x = robot.get_pose().x
    await store.put("part")
    await fleet_sim.sleep(1.0)
    assert store.items == ["part"]  # nobody took it on behalf of the cancelled mission
    assert robot.get_pose().x == x  # the robot stopped when its mission stopped waiting


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_predicate_that_lost_an_any_of_does_not_hide_a_deadlock(backend):
    with _sim() as sim:

        async def main():
            await sim.any_of(sim.wait_until(lambda: False), sim.timeout(2))
            await fa.Event(sim)  # nothing will set it

        with pytest.raises(fa.MissionDeadlockError):
            fa.run(sim, main, backend=backend)
        assert sim.sim_time == 2.0


@pytest.mark.parametrize("backend", BACKENDS)
def test_an_event_made_before_the_run_composes(backend):
    with _sim() as sim:
        ready = fa.Event(sim)

        async def setter():
            await sim.sleep(1)
            ready.set("go")

        async def main():
            sim.spawn(setter)
            first = await sim.any_of(ready, sim.timeout(5))
            second = await (ready | sim.timeout(5))
            return list(first.values()), list(second.values()), sim.now

        assert fa.run(sim, main, backend=backend) == (["go"], ["go"], 1.0)


# ----- stores and containers ----------------------------------------------------------------


async def test_giving_back_a_served_get_never_overfills(fleet_sim):
    shelf = fa.Store(fleet_sim, capacity=1)
    tank = fa.Container(fleet_sim, capacity=5, init=5)
    await shelf.put("a")

    async def take():
        await shelf.get()  # served at once: "a" leaves the shelf; processed later

    async def drain():
        await tank.get(5)

    takers = [fleet_sim.spawn(take), fleet_sim.spawn(drain)]
    await fleet_sim.sleep(0)  # the takers start, their gets are served, not yet processed
    assert shelf.items == [] and tank.level == 0
    shelf.put("b")  # the room they left is taken again
    tank.put(5)
    for taker in takers:
        taker.cancel()  # URGENT: they stop waiting before their grants are processed
    await fleet_sim.sleep(0)
    assert shelf.items == ["b"] and tank.level == 5  # never over capacity
    assert [r.item for r in shelf.put_queue] == ["a"]  # "a" waits first in line for room
    assert [r.amount for r in tank.put_queue] == [5]
    assert await shelf.get() == "b"
    await fleet_sim.sleep(0)
    assert shelf.items == ["a"]  # given back as soon as there was room


# ----- streams ----------------------------------------------------------------------------------


async def test_streams_share_items_between_readers_and_end_on_close(fleet_sim):
    robot = _robot(fleet_sim)
    got = []
    stream = fleet_sim.events.stream("action_completed")

    async def reader(name):
        async for _ in stream:
            got.append((name, round(fleet_sim.now, 1)))
        got.append((name, "end"))

    async with fleet_sim.task_group() as tg:
        tg.start_soon(reader, "r1")
        tg.start_soon(reader, "r2")
        for _ in range(4):
            await robot.wait(0.5)
        stream.close()
    assert got == [
        ("r1", 0.5),
        ("r2", 1.0),
        ("r1", 1.5),
        ("r2", 2.0),
        ("r2", "end"),  # r2 finds the stream closed when it comes back for more
        ("r1", "end"),  # r1 was waiting: its end arrives as an event
    ]


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_stream_left_open_is_closed_with_the_run(backend):
    with _sim() as sim:
        robot = _robot(sim)
        streams = []

        async def main():
            streams.append(sim.events.stream("action_completed"))
            await robot.wait(1.0)

        fa.run(sim, main, backend=backend)
        robot.add_action(fa.WaitAction(duration=1.0))
        for _ in range(20):
            sim.step_once()
        assert not sim.events.has_handlers("action_completed") or streams[0]._closed


# ----- missions and groups ------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_joined_spawn_failure_is_the_joiners_as_in_simpy(backend):
    def simpy_log():
        env, log = simpy.Environment(), []

        def child():
            yield env.timeout(1)
            raise ValueError("boom")

        def parent():
            try:
                yield env.process(child())
            except ValueError as error:
                log.append((env.now, "handled", str(error)))
            yield env.timeout(1)
            log.append((env.now, "main done"))

        env.process(parent())
        env.run()
        return log

    with _sim() as sim:
        log = []

        async def child():
            await sim.sleep(1)
            raise ValueError("boom")

        async def main():
            try:
                await sim.spawn(child)
            except ValueError as error:
                log.append((sim.now, "handled", str(error)))
            await sim.sleep(1)
            log.append((sim.now, "main done"))

        fa.run(sim, main, backend=backend)
        assert log == simpy_log()

        async def unjoined():
            sim.spawn(child)
            await sim.sleep(5)

        with pytest.raises(ValueError, match="boom"):  # nobody joined it: the run fails
            fa.run(sim, unjoined, backend=backend)


async def test_an_interrupt_in_a_groups_exit_wait_comes_as_the_body_s(fleet_sim):
    async def body_interrupted():
        async with fleet_sim.task_group() as tg:
            tg.start_soon(fleet_sim.sleep, 1.0)
            await fleet_sim.sleep(5.0)

    async def exit_interrupted():
        async with fleet_sim.task_group() as tg:
            tg.start_soon(fleet_sim.sleep, 5.0)

    for program in (body_interrupted, exit_interrupted):
        mission = fleet_sim.spawn(program)
        await fleet_sim.sleep(0.5)
        mission.interrupt("stop")
        with pytest.raises(BaseExceptionGroup) as caught:
            await mission
        assert [type(e) for e in caught.value.exceptions] == [fa.Interrupt]


async def test_a_scope_left_open_in_an_async_generator_is_named(fleet_sim):
    async def ticks():
        with fleet_sim.move_on_after(10):
            while True:
                await fleet_sim.sleep(1)
                yield fleet_sim.now

    async def consumer():
        async for _ in ticks():
            break  # the generator stays suspended inside its scope
        await fleet_sim.sleep(20)

    with pytest.raises(RuntimeError, match="never left: an async generator"):
        await fleet_sim.spawn(consumer)


async def test_a_preempted_holder_leaves_async_with_by_its_interrupt(fleet_sim):
    crane = fa.PreemptiveResource(fleet_sim, capacity=1)
    log = []

    async def low():
        try:
            async with crane:
                await fleet_sim.sleep(5)
        except fa.Interrupt as interrupt:
            log.append(("preempted", type(interrupt.cause).__name__))

    async def high():
        await fleet_sim.sleep(1)
        with crane.request(priority=-1) as req:
            await req
            log.append(("high", round(fleet_sim.now, 1)))

    async with fleet_sim.task_group() as tg:
        tg.start_soon(low)
        tg.start_soon(high)
    assert log == [("preempted", "Preempted"), ("high", 1.0)]
    assert crane.count == 0


# ----- the run's end ----------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_until_returns_mains_result_and_leaves_shielded_timers_due_then(backend):
    with _sim() as sim:

        async def quick():
            await sim.sleep(2)
            return "main's result"

        assert fa.run(sim, quick, until=10.0, backend=backend) == "main's result"

        log = []

        async def shielded():
            with sim.cancel_scope(shield=True):
                await sim.sleep(5)  # due exactly at until: not resumed
                log.append("resumed")

        start = sim.sim_time
        assert fa.run(sim, shielded, until=start + 5, backend=backend) is None
        assert log == []


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_scope_left_early_does_not_delay_a_deadlock(backend):
    with _sim(dt=0.1) as sim:

        async def main():
            with sim.move_on_after(300):
                await sim.sleep(0.1)
            await fa.Event(sim)

        with pytest.raises(fa.MissionDeadlockError):
            fa.run(sim, main, backend=backend)
        assert sim.step_count == 1


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_run_cancelled_from_outside_closes_its_missions(backend):
    with _sim() as sim:
        desk = fa.Resource(sim)
        log = []

        async def holder():
            async with desk.request():
                try:
                    await anyio.Event().wait()  # holds the clock until the host cancels
                finally:
                    log.append("holder finally")

        async def app():
            async with anyio.create_task_group() as tg:

                async def stopper():
                    for _ in range(20):
                        await anyio.lowlevel.checkpoint()
                    tg.cancel_scope.cancel()

                tg.start_soon(stopper)
                await fa.run_async(sim, holder)

        anyio.run(app, backend=backend)
        assert log == ["holder finally"]
        assert desk.count == 0 and sim.mission_runtime is None

        async def again():
            async with desk.request():
                return "got the slot"

        assert fa.run(sim, again, backend=backend) == "got the slot"


@pytest.mark.parametrize("backend", BACKENDS)
def test_keyboard_interrupt_in_a_step_is_raised_as_itself_after_cleanup(backend):
    with _sim() as sim:
        log = []

        def boom(sim, dt):
            raise KeyboardInterrupt

        async def worker():
            try:
                await sim.sleep(10)
            finally:
                log.append("worker finally")

        async def main():
            sim.register_callback(boom, frequency=1.0)
            await worker()

        with pytest.raises(KeyboardInterrupt):
            fa.run(sim, main, backend=backend)
        assert log == ["worker finally"]
        sim.unregister_callback(boom)


def test_a_cancelled_library_future_is_the_missions_error_not_a_stop():
    with _sim() as sim:
        log = []

        async def other():
            try:
                await sim.sleep(1)
            finally:
                log.append("other finally")

        async def main():
            sim.spawn(other)
            future = asyncio.get_running_loop().create_future()
            future.cancel()  # a library cancelled what this mission awaited
            await future

        with pytest.raises(asyncio.CancelledError):
            fa.run(sim, main, backend="asyncio")
        assert log == ["other finally"]


# ----- pacing and the outside world -------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_paced_run_lets_the_outside_world_set_an_event(backend, monkeypatch):
    run_module = sys.modules["fleet_async.tasks.driver"]
    wall = {"now": 0.0}

    async def fake_sleep(seconds):
        wall["now"] += seconds
        await anyio.lowlevel.checkpoint()

    monkeypatch.setattr(run_module, "_wall_clock", lambda: wall["now"])
    monkeypatch.setattr(run_module, "_wall_sleep", fake_sleep)
    with _sim(dt=0.1, rtf=1.0) as sim:
        operator = fa.Event(sim)

        async def main():
            return await operator, sim.step_count

        async def app():
            async with anyio.create_task_group() as tg:

                async def press_button():
                    for _ in range(5):
                        await anyio.lowlevel.checkpoint()
                    operator.set("go")

                tg.start_soon(press_button)
                return await fa.run_async(sim, main)

        value, steps = anyio.run(app, backend=backend)
        assert value == "go" and steps > 0  # paced: the clock ran while it waited


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_paced_run_behind_real_time_still_lets_other_tasks_run(backend, monkeypatch):
    run_module = sys.modules["fleet_async.tasks.driver"]
    wall = itertools.count(0.0, 100.0)  # every look at the wall: 100 s later, always behind
    monkeypatch.setattr(run_module, "_wall_clock", lambda: next(wall))
    monkeypatch.setattr(run_module, "_YIELD_EVERY", 0.0)
    with _sim(dt=0.1, rtf=1.0) as sim:
        ticks = []

        async def main():
            await sim.sleep(2.0)

        async def app():
            async with anyio.create_task_group() as tg:

                async def other():
                    while True:
                        ticks.append(1)
                        await anyio.lowlevel.checkpoint()

                tg.start_soon(other)
                await fa.run_async(sim, main)
                tg.cancel_scope.cancel()

        anyio.run(app, backend=backend)
        assert len(ticks) >= 10  # one turn per step at least


# ----- misuse -----------------------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_sim_await_from_another_thread_says_so(backend):
    with _sim() as sim:

        async def main():
            caught = []

            def other_thread():
                async def coro():
                    await sim.sleep(1)

                try:
                    asyncio.run(coro())
                except fa.NoMissionRuntimeError as error:
                    caught.append(str(error))

            thread = threading.Thread(target=other_thread)
            thread.start()
            thread.join()
            return caught

        [message] = fa.run(sim, main, backend=backend)
        assert "another thread" in message and "anyio.from_thread" in message


@pytest.mark.parametrize("backend", BACKENDS)
def test_awaiting_outside_a_mission_is_one_error_type_naming_the_call(backend):
    """Made before a run is fine (SimPy builds models first); awaited outside a mission is an
    error that names what was awaited, and an action awaited there does not drive on."""
    with _sim() as sim:
        robot = _robot(sim)
        for make, name in (
            (lambda: sim.sleep(1), "awaiting a sim event"),
            (lambda: robot.move(Pose.from_xyz(1, 0, 0.1)), r"agent\.move\(\.\.\.\)"),
            (lambda: fa.Resource(sim).request(), "awaiting a sim event"),
        ):
            event = make()

            async def outside(event=event):
                await event

            with pytest.raises(fa.NoMissionRuntimeError, match=name):
                anyio.run(outside, backend=backend)
        assert not robot.is_moving and robot.get_current_action() is None
        flag = fa.Event(sim)
        flag.fail(KeyError("early"))  # like set(): fine before the run
        flag.defused = True  # nobody will wait on it
        assert flag.triggered and not flag.ok

        def generator():
            yield 1

        with pytest.raises(TypeError, match="not SimPy generators"):
            fa.run(sim, generator())


def test_an_unknown_or_missing_backend_is_a_clear_error(monkeypatch):
    with _sim() as sim:

        async def main():
            await sim.sleep(1.0)

        with pytest.raises(ValueError, match=r'backend must be "asyncio" or "trio", got \'curio\''):
            fa.run(sim, main, backend="curio")
        real = importlib.util.find_spec
        monkeypatch.setattr(
            importlib.util, "find_spec", lambda name, *a: None if name == "trio" else real(name, *a)
        )
        with pytest.raises(ModuleNotFoundError, match=r'pip install "fleet-async\[trio\]"'):
            fa.run(sim, main, backend="trio")
        assert sim.step_count == 0  # nothing ran


@pytest.mark.parametrize("backend", BACKENDS)
def test_missions_waiting_on_actions_only_skip_the_empty_steps(backend, monkeypatch):
    # No mission event is due while the robot waits 100 s in a WaitAction: the driver asks the
    # simulation (which knows the action's timer) and jumps, with the same result and clock.
    with _sim(dt=0.1) as sim:
        robot = _robot(sim)
        calls = 0
        step_once = sim.step_once

        def counted(*args, **kwargs):
            nonlocal calls
            calls += 1
            return step_once(*args, **kwargs)

        monkeypatch.setattr(sim, "step_once", counted)

        async def main():
            await robot.wait(100.0)
            return sim.sim_time

        assert fa.run(sim, main, backend=backend) == pytest.approx(100.0)
        assert sim.step_count == 1000
        assert calls < 10  # about 1,000 before
