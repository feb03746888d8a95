"""The transport-neutral fleet interface, driven from Python (the in-memory transport)."""

from __future__ import annotations

import math
import threading

import pytest

from fleet_async import Agent, BatteryPlugin, Pose, ShapeParams, SimObject
from fleet_async.interfaces import (
    Blocking,
    Edge,
    FleetInterface,
    InMemoryTransport,
    InstantTasks,
    Node,
    Order,
    Rejection,
    Task,
    TaskStatus,
)

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
SMALL = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def robot(sim, name="r0", xyz=(0.0, 0.0, 0.1), controller="omni"):
    return Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(*xyz), sim_core=sim, controller=controller, name=name
    )


def route(
    order_id="o1",
    points=((0, 0), (2, 0), (2, 2)),
    released=None,
    update=0,
    tasks=None,
    first=0,
    **edge_kw,
):
    """An order through ``points``; ``released`` nodes released (default all)."""
    released = len(points) if released is None else released
    tasks = tasks or {}
    nodes = tuple(
        Node(
            f"n{first + i}",
            2 * (first + i),
            i < released,
            float(x),
            float(y),
            tasks=tuple(tasks.get(i, ())),
        )
        for i, (x, y) in enumerate(points)
    )
    edges = tuple(
        Edge(
            f"e{first + i}",
            2 * (first + i) + 1,
            f"n{first + i}",
            f"n{first + i + 1}",
            released=i + 1 < released,
            **edge_kw,
        )
        for i in range(len(points) - 1)
    )
    return Order(order_id, update, nodes, edges)


@pytest.fixture
def served(sim):
    agent = robot(sim)
    fleet = FleetInterface(sim, state_period=30.0, visualization_period=0)
    return sim, agent, fleet, InMemoryTransport(fleet)


def steps(sim, n):
    for _ in range(n):
        sim.step_once()


def reasons(link, name="r0"):
    return [(snap.step, why) for snap, why in link.states[name]]


def test_an_order_is_driven_node_by_node_to_the_end(served):
    sim, agent, fleet, link = served
    link.send("r0", route())
    steps(sim, 5)
    assert fleet._active == {"r0"}  # followed up on each step while it works
    steps(sim, 195)
    assert fleet._active == set()  # done: an idle vehicle costs a step nothing
    reached = [
        (snap.last_node_id, snap.last_node_sequence)
        for snap, why in link.states["r0"]
        if "node_reached" in why
    ]
    assert reached == [("n0", 0), ("n1", 2), ("n2", 4)]
    pose = agent.get_pose()
    assert (pose.x, pose.y) == pytest.approx((2.0, 2.0), abs=1e-9)
    last = link.latest("r0")
    assert last.nodes == () and last.edges == () and not last.driving
    assert last.order_id == "o1" and last.errors == ()
    # The order was taken at the first step boundary, before step 1 ran.
    assert reasons(link)[0][0] == 0 and "order_accepted" in reasons(link)[0][1]


def test_the_vehicle_waits_at_the_end_of_the_base_until_an_update_releases_more(served):
    sim, agent, _, link = served
    link.send("r0", route(points=((0, 0), (2, 0), (4, 0)), released=2))
    steps(sim, 150)
    waiting = link.latest("r0")
    assert waiting.last_node_id == "n1" and not waiting.driving
    assert waiting.nodes == (("n2", 4, False),) and waiting.edges == (("e1", 3, False),)
    assert agent.get_pose().x == pytest.approx(2.0, abs=1e-9)
    update = route(points=((2, 0), (4, 0)), update=1, first=1)
    link.send("r0", update)
    steps(sim, 150)
    assert agent.get_pose().x == pytest.approx(4.0, abs=1e-9)
    assert link.latest("r0").last_node_id == "n2" and link.latest("r0").order_update == 1


def test_update_rules_older_equal_and_unstitched(served):
    sim, _, _, link = served
    link.send("r0", route(points=((0, 0), (2, 0), (4, 0)), released=2, update=3))
    steps(sim, 2)
    link.send("r0", route(points=((0, 0), (2, 0), (4, 0)), released=2, update=1))  # older
    link.send("r0", route(points=((0, 0), (2, 0), (4, 0)), released=2, update=3))  # same: ignored
    link.send("r0", route(points=((4, 0), (6, 0)), update=4, first=2))  # not at the base's end
    steps(sim, 1)
    errors = link.latest("r0").errors
    assert [e.kind for e in errors] == ["order_update", "order_update"]
    assert "older than the update 3" in errors[0].description
    assert ("order_update", "1") in errors[0].references
    assert "must start at the last released node ('n1', 2)" in errors[1].description
    link.send("r0", route(points=((2, 0), (4, 0)), update=4, first=1))
    steps(sim, 1)
    assert link.latest("r0").errors == () and link.latest("r0").order_update == 4


@pytest.mark.parametrize(
    ("order", "expected"),
    [
        (Order("bad", 0, ()), "has no nodes"),
        (
            Order(
                "bad",
                0,
                (Node("a", 0, x=0.0, y=0.0), Node("b", 4, x=1.0, y=0.0)),
                (Edge("e", 1, "a", "b"),),
            ),
            "expected 2 (nodes and edges alternate)",
        ),
        (
            Order("bad", 0, (Node("a", 0, x=0.0, y=0.0), Node("b", 2)), (Edge("e", 1, "a", "b"),)),
            "node 'b' has no position",
        ),
        (
            Order(
                "bad",
                0,
                (Node("a", 0, x=0.0, y=0.0), Node("b", 2, x=1.0, y=0.0)),
                (Edge("e", 1, "b", "a"),),
            ),
            "joins 'b' to 'a'",
        ),
        (route(tasks={1: [Task("dance", "t1")]}), "kind 'dance' is not supported"),
        (route(tasks={1: [Task("pick", "t1", Blocking.NONE)]}), "cannot run while driving"),
        (route(points=((5, 5), (6, 5))), "is 7.071 m from the vehicle"),
    ],
)
def test_orders_that_cannot_run_are_refused_with_the_reason(served, order, expected):
    sim, agent, _, link = served
    link.send("r0", order)
    steps(sim, 3)
    (error,) = link.latest("r0").errors
    assert error.kind == "order" and expected in error.description
    assert ("order_id", "bad" if order.order_id == "bad" else "o1") in error.references
    assert agent.get_pose().x == 0.0 and not link.latest("r0").driving


def test_a_new_order_while_busy_is_refused(served):
    sim, _, _, link = served
    link.send("r0", route())
    steps(sim, 5)
    link.send("r0", route(order_id="o2"))
    steps(sim, 1)
    (error,) = link.latest("r0").errors
    assert error.kind == "order" and "still on order 'o1'" in error.description
    assert link.latest("r0").order_id == "o1"


def test_cancel_stops_the_robot_in_that_step_and_keeps_the_order_id(served):
    sim, agent, fleet, link = served
    link.send("r0", route(points=((0, 0), (8, 0))))
    steps(sim, 20)
    link.send("r0", InstantTasks((Task("cancel_order", "c1"),)))
    steps(sim, 1)  # applied at the boundary before this step ran
    stopped = agent.get_pose().x
    steps(sim, 20)
    assert agent.get_pose().x == stopped and 0.0 < stopped < 8.0
    snap = link.latest("r0")
    assert snap.order_id == "o1" and snap.nodes == () and snap.edges == ()
    assert {t.task_id: t.status for t in snap.tasks}["c1"] is TaskStatus.FINISHED
    link.send("r0", InstantTasks((Task("cancel_order", "c2"),)))
    steps(sim, 1)
    snap = link.latest("r0")
    assert {t.task_id: t.status for t in snap.tasks}["c2"] is TaskStatus.FAILED
    (error,) = snap.errors
    assert error.kind == "no_order_to_cancel" and error.references == (("task_id", "c2"),)
    assert not fleet.vehicles["r0"].has_order


def test_pause_freezes_the_robot_and_resume_finishes_the_order(served):
    sim, agent, _, link = served
    link.send("r0", route(points=((0, 0), (4, 0))))
    steps(sim, 10)
    link.send("r0", InstantTasks((Task("start_pause", "p1"),)))
    steps(sim, 1)
    frozen = agent.get_pose().x
    steps(sim, 30)
    assert agent.get_pose().x == frozen and link.latest("r0").paused
    link.send("r0", InstantTasks((Task("stop_pause", "p2"),)))
    steps(sim, 100)
    assert agent.get_pose().x == pytest.approx(4.0, abs=1e-9)
    assert not link.latest("r0").paused and link.latest("r0").last_node_id == "n1"


def test_pick_at_one_node_and_drop_at_another(served):
    sim, agent, _, link = served
    tote = SimObject.from_mesh(
        SMALL, SMALL, Pose.from_xyz(2.0, 0.0, 0.1), sim_core=sim, name="tote"
    )
    tasks = {1: [Task("pick", "pick1", params={"load_id": "tote"})], 2: [Task("drop", "drop1")]}
    link.send("r0", route(tasks=tasks))
    steps(sim, 300)
    states = {t.task_id: t.status for t in link.latest("r0").tasks}
    assert states == {"pick1": TaskStatus.FINISHED, "drop1": TaskStatus.FINISHED}
    carried = [snap.loads for snap, why in link.states["r0"] if snap.loads]
    assert carried and carried[0][0].load_id == "tote"
    assert link.latest("r0").loads == ()
    pose = tote.get_pose()
    assert (pose.x, pose.y, pose.z) == pytest.approx((2.0, 2.0, 0.1), abs=1e-6)  # as it stood
    assert not tote.is_attached() and agent.get_attached_objects() == []


def test_a_pick_with_nothing_in_reach_fails_and_the_order_goes_on(served):
    sim, _, _, link = served
    link.send("r0", route(tasks={1: [Task("pick", "pick1")]}))
    steps(sim, 300)
    task = {t.task_id: t for t in link.latest("r0").tasks}["pick1"]
    assert task.status is TaskStatus.FAILED and task.description == "nothing to pick"
    assert link.latest("r0").last_node_id == "n2"


def test_charging_needs_a_battery(sim):
    robot(sim, "plain")
    charged = robot(sim, "charged", xyz=(3.0, 0.0, 0.1))
    charged.add_plugin(BatteryPlugin(charged, {"initial_soc": 0.5}))
    fleet = FleetInterface(sim, visualization_period=0)
    link = InMemoryTransport(fleet)
    for name in ("plain", "charged"):
        link.send(name, InstantTasks((Task("start_charging", "ch"),)))
    steps(sim, 1)
    plain = {t.task_id: t for t in link.latest("plain").tasks}["ch"]
    assert plain.status is TaskStatus.FAILED and "no battery" in plain.description
    assert link.latest("charged").charging and link.latest("charged").battery_charge == 50.0


def test_init_position_sets_the_pose_and_last_node(served):
    sim, agent, _, link = served
    params = {"x": 3.0, "y": 1.0, "theta": 1.5, "last_node_id": "dock", "map_id": "floor1"}
    link.send("r0", InstantTasks((Task("init_position", "i1", params=params),)))
    steps(sim, 1)
    pose = agent.get_pose()
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((3.0, 1.0, 1.5))
    assert link.latest("r0").last_node_id == "dock"


def test_edge_speed_limit_caps_the_robot(served):
    sim, agent, _, link = served
    link.send("r0", route(points=((0, 0), (6, 0)), max_speed=0.5))
    top = 0.0
    for _ in range(100):
        sim.step_once()
        top = max(top, abs(float(agent.velocity[0])))
    assert top == pytest.approx(0.5, abs=1e-9)


def test_rejections_from_a_transport_become_errors_until_an_order_is_accepted(served):
    sim, _, _, link = served
    link.send("r0", Rejection("validation", "order: not JSON", (("topic", "order"),)))
    steps(sim, 1)
    assert [e.kind for e in link.latest("r0").errors] == ["validation"]
    link.send("r0", route())
    steps(sim, 1)
    assert link.latest("r0").errors == ()


def test_commands_from_other_threads_apply_at_the_next_boundary_in_arrival_order(served):
    sim, agent, fleet, link = served
    arrived = threading.Event()

    def master():
        fleet.submit("r0", route(points=((0, 0), (8, 0))))
        fleet.submit("r0", InstantTasks((Task("cancel_order", "c1"),)))
        arrived.set()

    thread = threading.Thread(target=master)
    thread.start()
    assert arrived.wait(10)
    thread.join()
    steps(sim, 10)
    # Both applied before the first step: the order was taken, then cancelled; never moved.
    assert agent.get_pose().x == 0.0
    assert {t.task_id: t.status for t in link.latest("r0").tasks} == {"c1": TaskStatus.FINISHED}
    with pytest.raises(KeyError, match="'nobody' is not a served vehicle"):
        fleet.submit("nobody", route())


def test_state_period_and_visualization_rate(sim):
    robot(sim)
    fleet = FleetInterface(sim, state_period=2.0, visualization_period=0.5)
    link = InMemoryTransport(fleet)
    steps(sim, 50)  # 5 s: states at 0, 2 and 4 s; visualizations every 0.5 s
    assert [snap.step for snap, why in link.states["r0"]] == [0, 20, 40]
    assert all(why == ("periodic",) for _, why in link.states["r0"])
    assert link.visualizations["r0"] == 10


def test_robot_names_are_checked(sim):
    robot(sim, "twin")
    robot(sim, "twin", xyz=(2.0, 0.0, 0.1))
    with pytest.raises(ValueError, match=r"'twin' names 2 robots"):
        FleetInterface(sim, ["twin"])
    with pytest.raises(ValueError, match=r"'ghost' names no robot"):
        FleetInterface(sim, ["ghost"])
    with pytest.raises(ValueError, match=r"state_period.*45"):
        FleetInterface(sim, [], state_period=45)
    # Serving every robot, a shared name is told apart by the robot's id, as the viewer does.
    ids = [a.object_id for a in sim.agents]
    assert list(FleetInterface(sim).vehicles) == [f"twin#{i}" for i in ids]


def test_edge_orientation_on_a_differential_robot(sim):
    agent = robot(sim, "diff", controller="differential")
    link = InMemoryTransport(FleetInterface(sim, visualization_period=0))
    link.send("diff", route(points=((0, 0), (2, 0)), orientation=1.0))
    steps(sim, 1)
    (error,) = link.latest("diff").errors
    assert "can only drive forward or backward" in error.description
    assert ("edge_id", "e0") in error.references
    # Backward (pi, tangential): it reverses to the node, still facing +x.
    link.send("diff", route(order_id="back", points=((0, 0), (-2, 0)), orientation=math.pi))
    steps(sim, 100)
    pose = agent.get_pose()
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((-2.0, 0.0, 0.0), abs=1e-6)
    assert link.latest("diff").errors == ()


def test_global_edge_orientation_on_an_omni_robot(served):
    sim, agent, _, link = served
    link.send("r0", route(points=((0, 0), (2, 0)), orientation=1.2, orientation_global=True))
    steps(sim, 100)
    pose = agent.get_pose()
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((2.0, 0.0, 1.2), abs=1e-6)
