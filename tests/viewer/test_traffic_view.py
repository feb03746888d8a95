"""Traffic in the viewer (headless Chromium): a robot in a safety stop is coloured "stopped"
and, selected, shows its protective and warning fields; the route graph is drawn under the
robots; a grid map shows its obstacle rectangles, not its tile bodies' bounding boxes."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleet_async import MultiRobotSimulationCore, Pose
from fleet_async.viewer import TraceReader
from tests.conftest import headless_params
from tests.core.traffic.test_safety_fields import robot, wall
from tests.viewer.test_timeline import READY, near, open_trace, pixel, rgb

DATA = Path(__file__).resolve().parents[1] / "data" / "traffic"
MAP_RGB = [89, 89, 102]  # traffic.js MAP_FILL (and maps/world.py's colour)


def layer_pixel(page, canvas, x, y):
    """[r, g, b, a] of canvas #grid or #overlay at world (x, y)."""
    p = page.evaluate(f"viewer.project({x}, {y})")
    return page.evaluate(
        f"""(() => {{ const c = document.getElementById('{canvas}');
        const d = window.devicePixelRatio || 1;
        return Array.from(c.getContext('2d').getImageData(
            Math.round({p["x"]} * d), Math.round({p["y"]} * d), 1, 1).data); }})()"""
    )


@pytest.fixture(scope="module")
def stop_trace(tmp_path_factory):
    """Robot "a" drives at a wall and stops in front of it; a route graph is in use."""
    path = tmp_path_factory.mktemp("stop") / "stop.fatrace"
    with MultiRobotSimulationCore(headless_params(enable_floor=True)) as sim:
        a = robot(sim, 0.0, name="a")
        wall(sim, 3.0)
        sim.load_route_graph(DATA / "loop.graph.yaml")
        graph = sim.route_graph
        sim.start_trace(path)
        a.set_path([Pose.from_xyz(5.0, 0.0, 0.2)])
        for _ in range(60):
            sim.step_once()
        assert sim.safety.is_stopped(a)
    return path, a.object_id, graph


def test_a_stopped_robot_is_marked_and_its_fields_drawn_when_selected(
    browser_page, serve, stop_trace
):
    path, rid, _ = stop_trace
    # It creeps up to the wall (short stops), then stays stopped: the last stop.
    stop = [e for e in TraceReader(path).events if e["kind"] == "safety_stop_started"][-1]
    page = browser_page
    open_trace(page, serve(path))
    page.evaluate(f"viewer.seek({stop['t'] + 0.5})")
    pose = page.evaluate(f"viewer.poseOf({rid})")
    states = page.evaluate("viewer.stateColours()")
    assert near(pixel(page, pose["x"] - 0.1, pose["y"] + 0.1), rgb(states, "stopped"))
    assert page.evaluate("viewer.traffic().fields") is None  # nothing selected
    page.evaluate(f"viewer.select({rid})")
    assert page.evaluate("document.getElementById('app').dataset.selectedState") == "stopped"
    fields = page.evaluate("viewer.traffic().fields")
    assert [[q["x"], q["y"]] for q in fields["protective"]] == stop["data"]["protective"]
    assert len(fields["warning"]) == 4
    # The protective field's centre is drawn red on the overlay.
    cx = sum(q["x"] for q in fields["protective"]) / 4
    cy = sum(q["y"] for q in fields["protective"]) / 4
    r, g, b, alpha = layer_pixel(page, "overlay", cx, cy)
    assert alpha > 0 and r > g and r > b
    # Before the stop: neither the mark nor the fields.
    page.evaluate("viewer.seek(0.5)")
    assert page.evaluate("viewer.traffic().fields") is None
    assert page.evaluate("document.getElementById('app').dataset.selectedState") != "stopped"
    page.evaluate("viewer.select(null)")


def test_the_route_graph_is_drawn_under_the_robots(browser_page, serve, stop_trace):
    path, _, graph = stop_trace
    page = browser_page
    open_trace(page, serve(path))
    page.evaluate("viewer.seek(1.0)")
    page.evaluate("viewer.fit()")
    drawn = page.evaluate("viewer.traffic()")
    visible = [
        n
        for n in graph.nodes.values()
        if 0 <= page.evaluate(f"viewer.project({n.x}, {n.y})")["x"] <= 1200
    ]
    assert drawn["nodes"] == len(graph.nodes) and drawn["edges"] == len(graph.edges)
    node = visible[0]
    r, g, b, alpha = layer_pixel(page, "grid", node.x, node.y)
    assert alpha > 100 and b > r and b > g  # the node's blue dot on the bottom canvas


def test_a_map_shows_its_rectangles_not_its_tiles_bounding_boxes(browser_page, serve, tmp_path):
    path = tmp_path / "map.fatrace"
    with MultiRobotSimulationCore(headless_params()) as sim:
        loaded = sim.load_map(DATA / "warehouse-small.map", resolution=0.5, tile=8.0)
        robot(sim, -2.0, name="outside", fields=None)
        sim.start_trace(path)
        sim.step_once()
        sim.stop_trace()
    bodies = TraceReader(path).bodies
    assert {b.object_id for b in loaded.bodies} <= set(bodies)  # still bodies in the trace
    page = browser_page
    page.goto(serve(path).url)
    page.wait_for_function(READY, timeout=60_000)
    page.evaluate("viewer.seek(0.1)")
    assert page.evaluate("viewer.traffic().rects") == len(loaded.lo)
    for lo, hi in zip(loaded.lo[:3], loaded.hi[:3], strict=True):
        got = layer_pixel(page, "grid", (lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2)
        assert near(got[:3], MAP_RGB) and got[3] > 150
    # Free cells inside the map's extent (aisles between shelf rows, most of them inside a
    # tile body's bounding box, which the viewer would otherwise fill): nothing drawn there.
    free = [loaded.cell_position(int(r), int(c)) for r, c in loaded.free_cells()]
    lo, hi = loaded.lo[:, :2].min(axis=0), loaded.hi[:, :2].max(axis=0)
    inside = [(x, y) for x, y, _ in free if lo[0] < x < hi[0] and lo[1] < y < hi[1]]
    assert len(inside) > 8
    for x, y in inside[:: len(inside) // 8]:
        assert layer_pixel(page, "grid", x, y)[3] == 0
        p = page.evaluate(f"viewer.project({x}, {y})")
        assert page.evaluate(f"viewer.pixelAt({p['x']}, {p['y']})")[3] == 0
