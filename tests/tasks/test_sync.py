"""Sim-aware Event, Resource / Lock, Store, event streams and action handles."""

from __future__ import annotations

import pytest

from fleet_async import ActionStatus, Agent, MoveAction, Pose, ShapeParams, SimEvents, WaitAction
from fleet_async.tasks import Event, Lock, Resource, Store

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def robot(sim, x=0.0, y=0.0):
    return Agent.from_mesh(BOX, BOX, Pose.from_xyz(x, y, 0.1), sim_core=sim, controller="omni")


async def test_event_wakes_every_waiter_in_key_order(fleet_sim):
    gate = Event(fleet_sim)
    woke = []

    async def waiter(tag):
        await gate.wait()
        woke.append((tag, fleet_sim.step_count))

    async def opener():
        await fleet_sim.sleep(0.5)
        gate.set()

    async with fleet_sim.task_group() as tg:
        tg.start_soon(waiter, "a")
        tg.start_soon(waiter, "b")
        tg.start_soon(opener)
    assert woke == [("a", 5), ("b", 5)] and gate.is_set()
    await gate.wait()  # already set: returns at once
    assert fleet_sim.step_count == 5


async def test_resource_hands_out_slots_by_priority_then_order(fleet_sim):
    charger = Resource(fleet_sim, capacity=1)
    log = []

    async def user(tag, priority, delay):
        await fleet_sim.sleep(delay)
        async with charger.request(priority=priority):
            log.append((tag, fleet_sim.step_count))
            await fleet_sim.sleep(1.0)

    async with fleet_sim.task_group() as tg:
        tg.start_soon(user, "first", 5, 0.0)
        tg.start_soon(user, "low", 5, 0.1)
        tg.start_soon(user, "urgent", 0, 0.2)
    assert log == [("first", 0), ("urgent", 10), ("low", 20)]
    assert charger.in_use == 0 and charger.queued == 0


async def test_lock_and_cancelled_waiter_leaves_the_queue(fleet_sim):
    lock = Lock(fleet_sim)
    await lock.acquire()
    with fleet_sim.move_on_after(0.5) as scope:
        async with lock.request():
            pytest.fail("the lock is held")
    assert scope.cancelled_caught and lock.queued == 0
    lock.release()
    async with lock.request():
        assert lock.in_use == 1
    with pytest.raises(RuntimeError, match="no slot"):
        lock.release()
    with pytest.raises(ValueError, match="capacity"):
        Resource(fleet_sim, capacity=0)


async def test_store_put_get_with_filter_and_capacity(fleet_sim):
    store = Store(fleet_sim, capacity=2)
    got = []

    async def consumer():
        got.append((await store.get(lambda item: item.startswith("b")), fleet_sim.step_count))
        got.append((await store.get(), fleet_sim.step_count))

    async def producer():
        await store.put("a1")
        await fleet_sim.sleep(0.3)
        await store.put("b1")
        await store.put("a2")
        await store.put("a3")  # full (a1, a2): waits until the consumer takes a1

    async with fleet_sim.task_group() as tg:
        tg.start_soon(consumer)
        tg.start_soon(producer)
    assert got == [("b1", 3), ("a1", 3)]
    assert list(store.items) == ["a2", "a3"]


async def test_event_stream_yields_every_matching_event(fleet_sim):
    agent = robot(fleet_sim)
    seen = []

    async def mover():
        await agent.move(Pose.from_xyz(1, 0, 0.1))
        await agent.wait(0.5)

    async with (
        fleet_sim.events.stream(SimEvents.ACTION_COMPLETED) as completions,
        fleet_sim.task_group() as tg,
    ):
        tg.start_soon(mover)
        async for payload in completions:
            seen.append((type(payload["action"]).__name__, fleet_sim.sim_time))
            if len(seen) == 2:
                break
    assert [name for name, _ in seen] == ["MoveAction", "WaitAction"]
    assert seen[1][1] - seen[0][1] == pytest.approx(0.5)


async def test_action_handle_await_cancel_and_progress(fleet_sim):
    agent = robot(fleet_sim)
    handle = agent.submit(WaitAction(duration=1.0))
    assert handle.status is ActionStatus.NOT_STARTED and handle.progress == 0.0
    await fleet_sim.sleep(0.5)
    assert handle.status is ActionStatus.IN_PROGRESS and handle.progress == pytest.approx(0.5)
    action = await handle
    assert action.status is ActionStatus.COMPLETED and handle.done and handle.progress == 1.0
    move = agent.submit(MoveAction(path=Pose.from_xyz(10, 0, 0.1)))
    await fleet_sim.sleep(0.3)
    move.cancel()
    assert move.status is ActionStatus.CANCELLED and not agent.is_moving
