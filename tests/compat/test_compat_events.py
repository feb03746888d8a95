"""Events as a pybullet_fleet script uses them (issue 15): where the seed is silent, the
incumbent's public behaviour (payload names, priority order, per-entity update events)."""

from __future__ import annotations

import pytest

from fleet_async.action import MoveAction, WaitAction
from fleet_async.agent import Agent
from fleet_async.events import EventBus, SimEvents
from fleet_async.geometry import Pose
from fleet_async.sim_object import ShapeParams
from fleet_async.types import ActionStatus

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def omni(sim, x=0.0, y=0.0, cls=Agent):
    return cls.from_mesh(BOX, BOX, Pose.from_xyz(x, y, 0.1), sim_core=sim, controller="omni")


def test_lower_priority_runs_first_and_equal_priorities_in_order():
    bus = EventBus()
    order = []
    for name, priority in (("p10", 10), ("p0a", 0), ("p-5", -5), ("p0b", 0)):
        bus.on("e", lambda name=name, **kw: order.append(name), priority=priority)
    bus.emit("e")
    assert order == ["p-5", "p0a", "p0b", "p10"]


def test_handlers_written_to_the_incumbent_payloads_run(sim):
    seen = []
    sim.events.on(SimEvents.PRE_STEP, lambda dt, sim_time: seen.append(("pre", dt, sim_time)))
    sim.events.on(SimEvents.POST_STEP, lambda dt, sim_time: seen.append(("post", dt, sim_time)))
    sim.events.on(
        SimEvents.COLLISION_STARTED, lambda obj_a, obj_b: seen.append(("hit", obj_a, obj_b))
    )

    class Bumper(Agent):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.events.on(SimEvents.COLLISION_STARTED, self._on_bump)

        def _on_bump(self, other):  # the per-entity payload is ``other``
            seen.append(("bump", other))

    a = omni(sim, cls=Bumper)
    b = omni(sim, x=0.3)
    sim.step_once()
    assert seen == [
        ("pre", 0.1, 0.0),
        ("hit", a, b),
        ("bump", b),
        ("post", 0.1, pytest.approx(0.1)),
    ]


def test_action_events_carry_the_status(sim):
    agent = omni(sim)
    seen = []
    sim.events.on(
        SimEvents.ACTION_COMPLETED,
        lambda agent, action, status: seen.append(("sim", type(action).__name__, status)),
    )
    agent.events.on(
        SimEvents.ACTION_COMPLETED,
        lambda action, status: seen.append(("agent", type(action).__name__, status)),
    )
    agent.events.on(SimEvents.ACTION_FAILED, lambda action, status: seen.append(("fail", status)))
    agent.add_action(WaitAction(duration=0.1))
    move = MoveAction(path=Pose.from_xyz(50, 0, 0.1))
    agent.add_action(move)
    for _ in range(3):
        sim.step_once()
    move.cancel()
    assert seen == [
        ("sim", "WaitAction", ActionStatus.COMPLETED),
        ("agent", "WaitAction", ActionStatus.COMPLETED),
        ("fail", ActionStatus.CANCELLED),
    ]


def test_per_entity_update_events_carry_dt_and_moved(sim):
    mover, idle = omni(sim), omni(sim, y=3.0)
    log = []
    for agent, name in ((mover, "mover"), (idle, "idle")):
        agent.events.on(SimEvents.PRE_UPDATE, lambda dt, name=name: log.append((name, "pre", dt)))
        agent.events.on(
            SimEvents.POST_UPDATE,
            lambda dt, moved, name=name: log.append((name, "post", dt, moved)),
        )
    mover.set_goal_pose(Pose.from_xyz(1, 0, 0.1))
    sim.step_once()
    assert log == [
        ("mover", "pre", 0.1),
        ("idle", "pre", 0.1),
        ("mover", "post", 0.1, True),
        ("idle", "post", 0.1, False),
    ]


def test_per_entity_update_events_cost_nothing_until_someone_listens(sim):
    agents = [omni(sim, x=i) for i in range(3)]
    assert not sim.world.has_update_listeners()
    agents[1].events.on(SimEvents.ACTION_COMPLETED, lambda **kw: None)  # another event
    assert not sim.world.has_update_listeners()

    def handler(dt, moved):
        pass

    agents[1].events.on(SimEvents.POST_UPDATE, handler)
    assert sim.world.has_update_listeners()
    agents[1].events.off(SimEvents.POST_UPDATE, handler)
    assert not sim.world.has_update_listeners()


def test_removal_is_told_on_the_object_bus_too(sim):
    agent = omni(sim)
    removed = []
    agent.events.on(SimEvents.OBJECT_REMOVED, lambda: removed.append("me"))
    sim.remove_object(agent)
    assert removed == ["me"]
