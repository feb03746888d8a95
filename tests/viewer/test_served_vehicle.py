"""A served vehicle in the viewer page: its order, task states, commands and route to go.

One robot is served (a fleet master sends it an order of 3 released nodes and 1 horizon node,
with a pick and a drop, then pauses and resumes it); another robot is not. Selecting the
served one while the order is in progress shows the order id, the nodes and edges still to
go, the task states and the commands received (clickable to jump to them), and draws its
route: solid to the released node, dashed and lighter to the horizon node.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimObject
from fleet_async.interfaces import (
    Edge,
    FleetInterface,
    InMemoryTransport,
    InstantTasks,
    Node,
    Order,
    Rejection,
    Task,
)
from fleet_async.viewer import TraceReader
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
SMALL = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])
POINTS = ((0.0, 0.0), (2.0, 0.0), (4.0, 0.0), (4.0, 2.0))
ROUTE_RGB = [0, 121, 107]  # viewer.js ROUTE_COLOUR
AT = 3.5  # s: n1 reached and the tote picked, on the way to n2
READY = "['ready', 'error'].includes(document.getElementById('app').dataset.state)"


def served_order() -> Order:
    tasks = {
        1: (Task("pick", "pick1", params={"load_id": "tote"}),),
        2: (Task("drop", "drop1"),),
    }
    nodes = tuple(
        Node(f"n{i}", 2 * i, i < 3, x, y, tasks=tasks.get(i, ())) for i, (x, y) in enumerate(POINTS)
    )
    edges = tuple(
        Edge(f"e{i}", 2 * i + 1, f"n{i}", f"n{i + 1}", released=i + 1 < 3)
        for i in range(len(POINTS) - 1)
    )
    return Order("ord1", 0, nodes, edges)


@pytest.fixture(scope="module")
def served_trace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """8 s: r0 served (order at step 5, pause at 10, resume at 15, a transport's rejection at
    60), 'other' not served."""
    path = tmp_path_factory.mktemp("traces") / "served.fatrace"
    sim = MultiRobotSimulationCore(headless_params())
    try:
        Agent.from_mesh(
            BOX, BOX, Pose.from_xyz(0.0, 0.0, 0.1), sim_core=sim, name="r0", controller="omni"
        )
        Agent.from_mesh(
            BOX, BOX, Pose.from_xyz(0.0, 3.0, 0.1), sim_core=sim, name="other", controller="omni"
        )
        SimObject.from_mesh(SMALL, SMALL, Pose.from_xyz(2.0, 0.0, 0.1), sim_core=sim, name="tote")
        link = InMemoryTransport(FleetInterface(sim, ["r0"], visualization_period=0))
        script = {
            5: served_order(),
            10: InstantTasks((Task("start_pause", "p1"),)),
            15: InstantTasks((Task("stop_pause", "p2"),)),
            60: Rejection("validation", "order: not JSON", (("topic", "order"),)),
        }
        sim.start_trace(path)
        for step in range(80):
            if step in script:
                link.send("r0", script[step])
            sim.step_once()
        sim.stop_trace()
    finally:
        sim.close()
    return path


def close(rgb, expected, tolerance=2):
    return all(abs(a - b) <= tolerance for a, b in zip(rgb, expected, strict=True))


def open_trace(page, server):
    page.goto(server.url)
    page.wait_for_function(READY, timeout=60_000)
    assert page.evaluate("viewer.state().error") is None


def body_id(reader: TraceReader, name: str) -> int:
    return next(i for i, b in reader.bodies.items() if b["name"] == name)


def state_at(reader: TraceReader, object_id: int, t: float) -> dict:
    states = [
        e
        for e in reader.events
        if e["kind"] == "vehicle_state" and e["object_id"] == object_id and e["t"] <= t + 1e-9
    ]
    return states[-1]["data"]


def click_body(page, reader, object_id, step):
    frame = next(f for f in reader.frames() if f.step == step)
    i = frame.ids.tolist().index(object_id)
    x, y = (float(v) for v in frame.position[i][:2])
    where = page.evaluate(f"viewer.project({x}, {y})")
    page.mouse.click(where["pageX"], where["pageY"])
    page.wait_for_function(f"document.getElementById('app').dataset.selected === '{object_id}'")


def test_a_served_vehicle_shows_its_order_tasks_commands_and_route(
    browser_page, serve, served_trace, tmp_path
):
    reader = TraceReader(served_trace)
    r0, other = body_id(reader, "r0"), body_id(reader, "other")
    # What the trace says at AT (the page must show the same).
    expected = state_at(reader, r0, AT)
    assert expected["order_id"] == "ord1" and expected["last_node"] == "n1"
    assert [n[:3] for n in expected["nodes"]] == [["n2", 4, True], ["n3", 6, False]]
    assert [c["step"] for c in reader.commands] == [5, 10, 15, 60]

    page = browser_page
    open_trace(page, serve(served_trace))
    parsed = page.evaluate(
        "viewer.data.commands.map("
        "(c) => [c.step, Number(c.t.toFixed(6)), c.vehicle, c.command.type])"
    )
    assert parsed == [
        [5, 0.5, "r0", "order"],
        [10, 1.0, "r0", "instant"],
        [15, 1.5, "r0", "instant"],
        [60, 6.0, "r0", "rejection"],
    ]

    # An unserved robot has no vehicle section and no route.
    page.evaluate(f"viewer.seek({AT})")
    click_body(page, reader, other, round(AT * 10))
    assert page.is_hidden("#sel-vehicle")
    assert page.evaluate("viewer.route()") is None

    # The served one, mid-order.
    click_body(page, reader, r0, round(AT * 10))
    assert page.is_visible("#sel-vehicle")
    assert page.get_attribute("#app", "data-order-id") == "ord1"
    order = page.inner_text("#sel-order")
    assert "order ord1" in order and "update 0" in order and "last node n1" in order
    assert "paused" not in order
    route_text = page.inner_text("#sel-route")
    assert "nodes to go: n2 | horizon n3" in route_text
    assert "edges to go: e1 | horizon e2" in route_text
    tasks = page.evaluate(
        "Array.from(document.querySelectorAll('#sel-tasks tbody tr'),"
        " (tr) => Array.from(tr.cells, (td) => td.textContent))"
    )
    assert tasks == [list(t) for t in expected["tasks"]]
    assert tasks[:2] == [["pick1", "pick", "finished"], ["drop1", "drop", "waiting"]]
    assert page.is_hidden("#sel-errors")

    # The commands received: time, type and ids; three are done by AT, the last of them current.
    commands = page.evaluate(
        "Array.from(document.querySelectorAll('#sel-commands li'),"
        " (li) => [li.textContent, li.className])"
    )
    assert [text for text, _ in commands] == [
        "0.50 s  order ord1 update 0: nodes n0 n1 n2 + horizon n3; tasks pick pick1, drop drop1",
        "1.00 s  instant start_pause p1",
        "1.50 s  instant stop_pause p2",
        "6.00 s  rejected validation: order: not JSON",
    ]
    assert [cls for _, cls in commands] == [
        "command order",
        "command instant",
        "command instant current",
        "command rejection future",
    ]
    assert "vehicle state: order ord1/0, last node n1" in page.inner_text("#sel-events")

    # The route: from the robot, solid to n2 (released), dashed and lighter to n3 (horizon).
    route = page.evaluate("viewer.route()")
    assert route["order_id"] == "ord1" and route["vehicle"] == "r0"
    assert [(p["node_id"], p["released"], p["x"], p["y"]) for p in route["points"]] == [
        ("n2", True, 4.0, 0.0),
        ("n3", False, 4.0, 2.0),
    ]
    pose = page.evaluate(f"viewer.poseOf({r0})")
    assert (route["from"]["x"], route["from"]["y"]) == pytest.approx((pose["x"], pose["y"]))
    assert 2.0 < pose["x"] < 4.0
    page.screenshot(path=str(tmp_path / "served_vehicle.png"))
    overlay = lambda x, y: page.evaluate(f"viewer.overlayPixelAt({x}, {y})")  # noqa: E731
    n2, n3 = route["points"]
    assert overlay(n2["px"], n2["py"]) == [*ROUTE_RGB, 255]  # released node: filled
    assert overlay(n3["px"], n3["py"]) == [255, 255, 255, 255]  # horizon node: hollow
    ring = page.evaluate("viewer.state().view.scale") * math.hypot(0.2, 0.2) + 8
    start = route["from"]
    solid = [
        overlay(start["px"] + (n2["px"] - start["px"]) * k, start["py"])
        for k in (i / 20 for i in range(1, 20))
        if (n2["px"] - start["px"]) * k > ring and (n2["px"] - start["px"]) * (1 - k) > 8
    ]
    assert len(solid) >= 3 and all(p == [*ROUTE_RGB, 255] for p in solid), solid
    dashed = [
        overlay(n2["px"], n2["py"] + (n3["py"] - n2["py"]) * k)
        for k in (i / 40 for i in range(4, 37))
    ]
    drawn = [p for p in dashed if p[3] > 0]
    assert drawn and len(drawn) < len(dashed)  # dashes with gaps
    # Lighter: half transparent (the canvas un-premultiplies alpha: +-2 per channel).
    assert all(close(p[:3], ROUTE_RGB) and 64 < p[3] < 200 for p in drawn), drawn

    # Clicking a command jumps to it: before the order took effect there is no order yet.
    page.click("#sel-commands li >> nth=0")
    page.wait_for_function(
        "Math.abs(Number(document.getElementById('app').dataset.simTime) - 0.5) < 1e-6"
    )
    assert page.inner_text("#sel-order") == "no order yet"
    assert page.get_attribute("#app", "data-route-nodes") == "0"
    assert page.evaluate("viewer.route()") is None
    classes = page.eval_on_selector_all("#sel-commands li", "(els) => els.map((e) => e.className)")
    assert classes == [
        "command order current",
        "command instant future",
        "command instant future",
        "command rejection future",
    ]
    # While paused (after 1.0 s) the panel says so, and every node is still to go.
    page.evaluate("viewer.seek(1.2)")
    assert "paused" in page.inner_text("#sel-order")
    assert "nodes to go: n1 n2 | horizon n3" in page.inner_text("#sel-route")
    # After the run: n3 is only on the horizon, so the vehicle waits at n2; the transport's
    # rejection is an error until the next order.
    page.evaluate("viewer.seek(1e9)")
    assert "last node n2" in page.inner_text("#sel-order")
    assert page.inner_text("#sel-errors") == "validation: order: not JSON"
    page.screenshot(path=str(tmp_path / "served_vehicle_end.png"))
    assert [p["node_id"] for p in page.evaluate("viewer.route()")["points"]] == ["n3"]
