"""Async missions: awaitables, sim-time primitives, cancellation, errors (both backends)."""

from __future__ import annotations

import sys

import anyio
import pytest

import fleet_async as fa
from fleet_async import (
    ActionCancelledError,
    ActionFailedError,
    ActionStatus,
    Agent,
    MissionDeadlockError,
    MissionStalledError,
    MoveAction,
    MultiRobotSimulationCore,
    Path,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    SimulationParams,
    WaitAction,
)
from fleet_async.tasks import Event

if sys.version_info < (3, 11):
    from exceptiongroup import BaseExceptionGroup

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
SMALL = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def robot(sim, x=0.0, y=0.0, name=None):
    return Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(x, y, 0.1), sim_core=sim, controller="omni", name=name
    )


# ----- sim-time primitives ----------------------------------------------------------------


async def test_sleep_and_sleep_until_advance_exact_steps(fleet_sim):
    await fleet_sim.sleep(0.5)
    assert fleet_sim.step_count == 5
    await fleet_sim.sleep(0.25)  # rounded up to whole steps
    assert fleet_sim.step_count == 8
    await fleet_sim.sleep_until(2.0)
    assert fleet_sim.step_count == 20
    await fleet_sim.sleep_until(1.0)  # already past: returns at once
    await fleet_sim.sleep(0)
    assert fleet_sim.step_count == 20


async def test_move_on_after_fires_at_the_exact_step(fleet_sim):
    with fleet_sim.move_on_after(1.0) as scope:
        await fleet_sim.sleep(10.0)
    assert scope.cancelled_caught and fleet_sim.step_count == 10
    with fleet_sim.move_on_after(5.0) as scope:
        await fleet_sim.sleep(1.0)
    assert not scope.cancelled_caught and fleet_sim.step_count == 20
    with fleet_sim.move_on_at(2.5) as scope:
        await fleet_sim.sleep(10.0)
    assert scope.cancelled_caught and fleet_sim.step_count == 25


async def test_fail_after_raises_timeout_error(fleet_sim):
    with pytest.raises(TimeoutError), fleet_sim.fail_after(0.3):
        await fleet_sim.sleep(1.0)
    assert fleet_sim.step_count == 3
    with pytest.raises(TimeoutError), fleet_sim.fail_at(0.5):
        await fleet_sim.sleep(1.0)
    assert fleet_sim.step_count == 5


async def test_nested_timeouts_and_shield(fleet_sim):
    with fleet_sim.move_on_after(1.0) as outer:
        with fleet_sim.move_on_after(0.5) as inner:
            await fleet_sim.sleep(3.0)
        assert inner.cancelled_caught and fleet_sim.step_count == 5
        with fleet_sim.cancel_scope(shield=True):
            await fleet_sim.sleep(1.0)  # shielded: runs past the outer deadline
        assert fleet_sim.step_count == 15
        await fleet_sim.sleep(1.0)
    assert outer.cancelled_caught and fleet_sim.step_count == 15


async def test_wait_until_checks_after_each_step(fleet_sim):
    agent = robot(fleet_sim)
    agent.set_goal_pose(Pose.from_xyz(3, 0, 0.1))
    await fleet_sim.wait_until(lambda: agent.get_pose().x >= 1.0)
    assert 1.0 <= agent.get_pose().x < 1.5
    await fleet_sim.wait_until(lambda: True)  # already true: no step
    assert agent.is_moving


async def test_events_wait_returns_the_matching_payload(fleet_sim):
    a, b = robot(fleet_sim, name="a"), robot(fleet_sim, y=2.0, name="b")

    async def drive():
        await b.move(Pose.from_xyz(0, 0.3, 0.1))

    async with fleet_sim.task_group() as tg:
        tg.start_soon(drive)
        payload = await fleet_sim.events.wait(
            SimEvents.COLLISION_STARTED, where=lambda obj_a, obj_b, **kw: b in (obj_a, obj_b)
        )
        assert {payload["obj_a"], payload["obj_b"]} == {a, b}
        assert 0.3 < b.get_pose().y < 0.45  # contact begins within the 0.02 m margin


# ----- agent awaitables ---------------------------------------------------------------------


async def test_move_returns_the_completed_action(fleet_sim):
    agent = robot(fleet_sim)
    action = await agent.move(Pose.from_xyz(2, 0, 0.1))
    assert isinstance(action, MoveAction) and action.status is ActionStatus.COMPLETED
    assert agent.get_pose().position.tolist() == [2.0, 0.0, 0.1]
    assert action.end_time == pytest.approx(fleet_sim.sim_time)
    path = Path.from_positions([[2, 1, 0.1], [0, 1, 0.1]])
    await agent.move(path, final_orientation_align=False)
    assert agent.get_pose().position.tolist() == [0.0, 1.0, 0.1]


async def test_wait_and_charge(fleet_sim):
    agent = robot(fleet_sim)
    start = fleet_sim.sim_time
    action = await agent.wait(1.2)
    assert isinstance(action, WaitAction) and fleet_sim.sim_time - start == pytest.approx(1.2)
    agent.add_plugin(fa.BatteryPlugin(agent, {"initial_soc": 0.5}))
    await agent.charge(0.5)
    assert not agent.is_charging


async def test_pick_and_drop(fleet_sim):
    agent = robot(fleet_sim)
    crate = SimObject.from_mesh(SMALL, SMALL, Pose.from_xyz(3, 0, 0.1), sim_core=fleet_sim)
    picked = await agent.pick(crate, attach_relative_pose=Pose.from_xyz(0, 0, 0.3))
    assert picked.picked_object is crate and crate.get_attached_parent() is agent
    await agent.drop(Pose.from_xyz(0, 3, 0.1))
    assert crate.get_pose() == Pose.from_xyz(0, 3, 0.1) and not crate.is_attached()


async def test_failed_action_raises_with_the_action(fleet_sim):
    agent = robot(fleet_sim)
    with pytest.raises(ActionFailedError, match="no pickable object") as info:
        await agent.pick(target_position=[9, 9, 0.1])
    assert info.value.action.status is ActionStatus.FAILED
    with pytest.raises(ActionFailedError, match="nothing is attached"):
        await agent.drop(Pose.from_xyz(1, 1, 0.1))


async def test_action_cancelled_from_outside_raises_a_catchable_error(fleet_sim):
    agent = robot(fleet_sim)
    action = MoveAction(path=Pose.from_xyz(10, 0, 0.1))

    async def meddler():
        await fleet_sim.sleep(0.5)
        action.cancel()

    async with fleet_sim.task_group() as tg:
        tg.start_soon(meddler)
        with pytest.raises(ActionCancelledError):
            await agent.submit(action)
    assert not agent.is_moving and fleet_sim.step_count == 5


async def test_timeout_cancels_the_running_action_and_stops_the_robot(fleet_sim):
    agent = robot(fleet_sim)
    with fleet_sim.move_on_after(1.0):
        await agent.move(Pose.from_xyz(10, 0, 0.1))
    assert fleet_sim.step_count == 10 and not agent.is_moving
    where = agent.get_pose().x
    assert agent.get_current_action() is None and agent.is_action_queue_empty()
    await fleet_sim.sleep(1.0)
    assert agent.get_pose().x == where  # nothing keeps moving on behalf of a dead mission


async def test_race_cancels_the_losers_and_their_actions(fleet_sim):
    fast, slow = robot(fleet_sim, name="fast"), robot(fleet_sim, y=3.0, name="slow")
    index, action = await fleet_sim.race(
        lambda: slow.move(Pose.from_xyz(10, 3, 0.1)),
        lambda: fast.move(Pose.from_xyz(1, 0, 0.1)),
    )
    assert index == 1 and action.status is ActionStatus.COMPLETED
    assert not slow.is_moving and slow.is_action_queue_empty()


async def test_gather_returns_results_in_order(fleet_sim):
    a, b = robot(fleet_sim), robot(fleet_sim, y=3.0)

    async def go(agent, x):
        await agent.move(Pose.from_xyz(x, agent.get_pose().y, 0.1))
        return fleet_sim.step_count

    results = await fleet_sim.gather(go(a, 4.0), go(b, 1.0))
    assert results[0] > results[1] and fleet_sim.step_count == results[0]


async def test_mission_rng_is_stable_per_mission(fleet_sim):
    draws = []

    async def draw():
        draws.append(fleet_sim.mission_rng().random())

    await fleet_sim.gather(draw, draw)
    again = []

    async def draw_again():
        again.append(fleet_sim.mission_rng().random())

    async with fleet_sim.task_group() as tg:
        tg.start_soon(draw_again)
    assert draws[0] != draws[1] and again[0] not in draws


# ----- errors and the runner ----------------------------------------------------------------


def _sim():
    return MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0.0))


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_run_returns_main_result_and_until_stops(backend):
    with _sim() as sim:

        async def main():
            await sim.sleep(1.0)
            return "done"

        assert fa.run(sim, main, backend=backend) == "done"
        assert sim.step_count == 10

        async def forever():
            while True:
                await sim.sleep(1.0)

        assert fa.run(sim, forever, until=sim.sim_time + 2.5, backend=backend) is None
        assert sim.step_count == 35


def _leaves(exc):
    """Every non-group exception inside ``exc``."""
    if isinstance(exc, BaseExceptionGroup):
        return [leaf for inner in exc.exceptions for leaf in _leaves(inner)]
    return [exc]


def _run_expecting(sim, main, backend, **kwargs):
    """Run and return the leaf exceptions the run raised (it must raise)."""
    try:
        fa.run(sim, main, backend=backend, **kwargs)
    except BaseException as exc:  # the test inspects what came out
        return _leaves(exc)
    raise AssertionError("the run was expected to raise")


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_exception_names_the_mission_and_sim_time(backend):
    with _sim() as sim:

        async def doomed():
            await sim.sleep(0.3)
            raise ValueError("boom")

        async def main():
            async with sim.task_group() as tg:
                tg.start_soon(doomed, name="doomed")

        [leaf] = _run_expecting(sim, main, backend)
        assert isinstance(leaf, ValueError)
        if hasattr(leaf, "add_note"):  # Python >= 3.11
            assert "in mission 'doomed' at sim time 0.300 s" in leaf.__notes__


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_deadlock_is_an_error_not_a_hang(backend):
    with _sim() as sim:

        async def stuck():
            # Waits on a sim Event that nothing will ever set.
            await fa.Event(sim).wait()

        async def main():
            async with sim.task_group() as tg:
                tg.start_soon(stuck, name="stuck")

        leaves = _run_expecting(sim, main, backend)
        assert any(isinstance(e, MissionDeadlockError) and "stuck" in str(e) for e in leaves)


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_wall_clock_wait_is_reported_by_the_watchdog(backend):
    with _sim() as sim:

        async def main():
            # A non-sim wait (here an event nobody sets) holds the clock; only the watchdog's
            # own wall-clock limit ends it.
            await anyio.Event().wait()

        leaves = _run_expecting(sim, main, backend, watchdog=0.05)
        assert any(isinstance(e, MissionStalledError) and "main" in str(e) for e in leaves)


def test_sim_awaits_outside_a_run_are_errors():
    with _sim() as sim:
        agent = robot(sim)
        with pytest.raises(RuntimeError, match=r"fleet_async\.run"):
            anyio.run(sim.sleep, 1.0)
        with pytest.raises(RuntimeError, match=r"fleet_async\.run"):
            anyio.run(agent.move, Pose.from_xyz(1, 0, 0.1))


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_real_io_holds_the_clock_and_run_async_works_in_a_loop(backend):
    """A mission awaiting something outside the simulation stops the clock until it is back."""
    with _sim() as sim:
        send, receive = anyio.create_memory_object_stream[str](1)
        seen = []

        async def outside_world():
            for _ in range(50):  # plenty of loop iterations: the sim must not step meanwhile
                await anyio.lowlevel.checkpoint()
            await send.send("reply")

        async def mission():
            await sim.sleep(0.5)
            before = sim.step_count
            seen.append(await receive.receive())
            seen.append(sim.step_count - before)
            await sim.sleep(0.5)
            return sim.step_count

        async def app():
            async with anyio.create_task_group() as tg:
                tg.start_soon(outside_world)
                result = await fa.run_async(sim, mission)
            return result

        assert anyio.run(app, backend=backend) == 10
        assert seen == ["reply", 0]


async def test_removing_an_agent_ends_the_awaited_action(fleet_sim):
    agent = robot(fleet_sim)

    async def remover():
        await fleet_sim.sleep(0.5)
        fleet_sim.remove_object(agent)

    async with fleet_sim.task_group() as tg:
        tg.start_soon(remover)
        with pytest.raises(ActionCancelledError, match="left the simulation"):
            await agent.move(Pose.from_xyz(10, 0, 0.1))
    assert fleet_sim.step_count == 5


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_pacing_follows_target_rtf_and_serves_wakes_from_outside(backend, monkeypatch):
    """At target_rtf 2 the driver sleeps so that wall time is half the sim time (on a fake
    wall clock). What the outside world does during a pacing sleep (here: set a sim Event)
    takes effect before the next step."""
    run_module = sys.modules["fleet_async.tasks.driver"]  # the module, not the function
    wall = {"now": 100.0}
    slept = []
    params = SimulationParams(gui=False, monitor=False, target_rtf=2.0, timestep=0.1)
    with MultiRobotSimulationCore(params) as sim:
        ready = Event(sim)

        async def fake_sleep(seconds):
            slept.append(seconds)
            wall["now"] += seconds
            if len(slept) == 3:  # the outside world acts while the driver paces step 3
                ready.set()
            await anyio.lowlevel.checkpoint()

        monkeypatch.setattr(run_module, "_wall_clock", lambda: wall["now"])
        monkeypatch.setattr(run_module, "_wall_sleep", fake_sleep)
        woke_at = []

        async def waiter():
            await ready.wait()
            woke_at.append(sim.step_count)

        async def main():
            async with sim.task_group() as tg:
                tg.start_soon(waiter)
                tg.start_soon(sim.sleep, 1.0)

        fa.run(sim, main, backend=backend)
        assert woke_at == [3]
        assert sim.step_count == 10
        assert len(slept) == 10  # one pacing sleep per step
        assert sum(slept) == pytest.approx(0.5)
        assert wall["now"] - 100.0 == pytest.approx(sim.sim_time / 2.0)


@pytest.mark.parametrize("watchdog", [0.0, -1.0, float("nan")])
def test_watchdog_must_be_positive(watchdog):
    with _sim() as sim:

        async def main():
            await sim.sleep(0.1)

        with pytest.raises(ValueError, match=r"watchdog must be a positive number.*got"):
            fa.run(sim, main, watchdog=watchdog)
        assert sim.step_count == 0


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_holding_the_clock_warns_once_naming_the_culprits(backend, monkeypatch):
    """A wall-clock wait inside a mission is allowed (it holds the clock) but gets one warning
    that names the mission and the sim-time replacements (the threshold, a second by default,
    is shortened here)."""
    monkeypatch.setattr(sys.modules["fleet_async.tasks.driver"], "_WARN_AFTER", 0.02)
    with _sim() as sim:

        async def main():
            # Wall clock on purpose: the watchdog looks every 0.25 s, so 0.6 s of holding
            # spans at least two of its looks.
            await anyio.sleep(0.6)
            await sim.sleep(0.1)
            return sim.step_count

        with pytest.warns(
            UserWarning,
            match=r"mission 'main' has held the simulation clock.*"
            r"anyio\.sleep.*sim\.sleep.*fleet_async\.Event, Lock",
        ):
            assert fa.run(sim, main, backend=backend, watchdog=2.0) == 1
