"""The viewer explains a robot's day: its timeline, the state palette, object kinds, names,
the legend, filters, labels and the goal drawn; and the warehouse screenshots (headless
Chromium, the page driven through its API and read back from the DOM and the pixels)."""

from __future__ import annotations

import concurrent.futures
import os
from pathlib import Path

import pytest

from fleet_async import (
    Agent,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimObject,
    SimulationParams,
    WaitAction,
)
from fleet_async.viewer import TraceReader

READY = "['ready', 'error'].includes(document.getElementById('app').dataset.state)"


def open_trace(page, server):
    page.goto(server.url)
    page.wait_for_function(READY, timeout=60_000)
    assert page.evaluate("viewer.state().error") is None


def rgb(colours, name):
    return [int(c * 255 + 0.5) for c in colours[name]]  # as the page rounds (half up)


def near(got, want):
    """Within one unit per channel (WebGL's float-to-byte conversion may differ by one)."""
    return all(abs(g - w) <= 1 for g, w in zip(got, want, strict=True))


def pixel(page, x, y):
    p = page.evaluate(f"viewer.project({x}, {y})")
    return page.evaluate(f"viewer.pixelAt({p['x']}, {p['y']})")[:3]


@pytest.fixture(scope="module")
def day_trace(tmp_path_factory):
    """Robots charging, waiting, idle and in a safety stop; a rack, a tote and a charger; two
    robots that share a name."""
    path = tmp_path_factory.mktemp("day") / "day.fatrace"
    cube = ShapeParams("box", half_extents=[0.3, 0.3, 0.1], rgba_color=[0.9, 0.1, 0.1, 1])
    params = SimulationParams(gui=False, monitor=False, target_rtf=0.0, enable_floor=False)
    with MultiRobotSimulationCore(params) as sim:
        robots = {
            name: Agent.from_mesh(
                cube, cube, Pose.from_xyz(2.0 * k, 0.0, 0.1), sim_core=sim, name=name
            )
            for k, name in enumerate(["charger_bot", "waiter", "idler", "stopper"])
        }
        twins = [
            Agent.from_mesh(cube, cube, Pose.from_xyz(2.0 * k, 3.0, 0.1), sim_core=sim, name="twin")
            for k in range(2)
        ]
        for name, x in (("rack_1", 0.0), ("tote_1", 2.0), ("charger_1", 4.0)):
            SimObject.from_mesh(
                cube,
                cube,
                Pose.from_xyz(x, -3.0, 0.1),
                sim_core=sim,
                name=name,
                pickable=name.startswith("tote"),
            )
        robots["charger_bot"].add_action(WaitAction(duration=5.0, action_type="charge"))
        robots["waiter"].add_action(WaitAction(duration=5.0))
        sim.start_trace(path)
        sim.step_once()
        sim.trace_event("safety_stop_started", robots["stopper"].object_id, reason="person ahead")
        for _ in range(20):
            sim.step_once()
        sim.trace_event("safety_stop_ended", robots["stopper"].object_id)
        for _ in range(40):
            sim.step_once()
        ids = {name: r.object_id for name, r in robots.items()}
        ids["twins"] = [t.object_id for t in twins]
    return path, ids


@pytest.mark.parametrize("renderer", ["canvas2d", "webgl2"])
def test_palette_tells_charging_waiting_stopped_and_object_kinds_apart(
    browser_page, serve, day_trace, renderer
):
    path, _ = day_trace
    page = browser_page
    page.goto(serve(path).url + f"?renderer={renderer}")
    page.wait_for_function(READY, timeout=60_000)
    page.evaluate("viewer.seek(1.0)")  # everyone mid-action; the stop lasts 0.1 .. 2.1 s
    states = page.evaluate("viewer.stateColours()")
    kinds = page.evaluate("viewer.objectColours()")
    # Off-centre (-0.15, +0.15): off the heading bar and the border.
    expected = {0.0: "charging", 2.0: "waiting", 4.0: "idle", 6.0: "stopped"}
    for x, state in expected.items():
        assert near(pixel(page, x - 0.15, 0.15), rgb(states, state)), state
    for x, kind in ((0.0, "rack"), (2.0, "tote"), (4.0, "charger")):
        assert near(pixel(page, x - 0.15, -3.0 + 0.15), rgb(kinds, kind)), kind
    # After the wait and the stop: all idle.
    page.evaluate("viewer.seek(6.0)")
    for x in expected:
        assert near(pixel(page, x - 0.15, 0.15), rgb(states, "idle"))


def test_legend_tells_the_truth_in_both_colour_modes(browser_page, serve, day_trace):
    path, _ = day_trace
    page = browser_page
    open_trace(page, serve(path))
    legend = page.evaluate("viewer.legend()")
    for name in ("idle", "moving", "carrying", "charging", "waiting", "stopped", "failed"):
        assert name in legend
    assert {"rack", "tote", "charger"} <= set(legend) and "station" not in legend  # none here
    assert "rack" in page.inner_text("#legend")
    page.evaluate("viewer.setColorMode('body')")
    assert page.evaluate("viewer.legend()") == [
        "colours as modelled in the scenario (robot states not shown)"
    ]
    page.evaluate("viewer.seek(1.0)")
    assert near(pixel(page, -0.15, 0.15), [230, 26, 26])  # as modelled: red, not "failed"
    page.evaluate("viewer.setColorMode('state')")


def test_shared_names_show_their_ids_and_the_timeline_filters(browser_page, serve, day_trace):
    path, ids = day_trace
    page = browser_page
    open_trace(page, serve(path))
    a, _ = ids["twins"]
    assert page.evaluate(f"viewer.displayName({a})") == f"twin#{a}"
    assert page.evaluate(f"viewer.displayName({ids['idler']})") == "idler"
    page.evaluate(f"viewer.select({a})")
    assert page.inner_text("#sel-name").startswith(f"twin#{a}")
    # The charging robot: its wait is a charging span; the stopper: a safety span.
    page.evaluate(f"viewer.select({ids['charger_bot']}); viewer.seek(1.0)")
    rows = page.evaluate("viewer.timeline()")
    assert [(r["kind"], r["text"]) for r in rows] == [("wait", "charging 5 s")]
    assert page.inner_text("#sel-doing") == "now charging: charging 5 s"
    page.evaluate(f"viewer.select({ids['waiter']})")
    assert [r["text"] for r in page.evaluate("viewer.timeline()")] == ["waiting 5 s"]
    page.evaluate(f"viewer.select({ids['stopper']})")
    assert [r["text"] for r in page.evaluate("viewer.timeline()")] == ["safety stop: person ahead"]
    assert "safety stop: person ahead" in page.inner_text("#sel-events")
    page.evaluate("viewer.setFilter('safety', false)")
    assert "safety stop" not in page.inner_text("#sel-events")
    assert "0 of 1 rows shown" in page.inner_text("#sel-count")
    page.evaluate("viewer.setFilter('safety', true)")
    # Labels on demand: names beside the robots.
    page.evaluate("viewer.select(null); viewer.setLabels(true)")
    assert int(page.get_attribute("#app", "data-labels")) == 6
    page.evaluate("viewer.setLabels(false)")


def test_warehouse_screenshots_and_the_first_pick_names_its_order_and_object(
    browser_page, tmp_path
):
    # Item of issue 31: headless Chromium opens the warehouse trace, selects a robot, and its
    # timeline names the order and the object of its first pick; three screenshots saved
    # (the docs' copies: python -m fleet_async.viewer.screenshots docs/images).
    from fleet_async.viewer.screenshots import MOMENTS, record_warehouse, take_screenshots

    # In a thread: playwright's sync API keeps an event loop running in this one, and the
    # shift's missions run on an event loop of their own.
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        trace = pool.submit(record_warehouse, tmp_path / "warehouse.fatrace").result()
    reader = TraceReader(trace)
    # CI keeps them where FLEET_ASYNC_SCREENSHOT_DIR points (an artifact folder), else a
    # temporary folder; the docs' copies come from the command above.
    out = Path(os.environ.get("FLEET_ASYNC_SCREENSHOT_DIR") or tmp_path / "shots")
    shots = take_screenshots(trace, out, page=browser_page)
    browser_page.set_viewport_size({"width": 1200, "height": 760})  # the session's size
    assert reader.bodies[shots.robot_id]["name"] == "picker_0"
    picks = [r for r in shots.timeline if r["text"].startswith("PickAction")]
    first = picks[0]["text"]
    # What the shift's log says: "picker_0 picked tote_A1_2 (order 2: tote_A1_2 to station_1)"
    # (the dispatcher gives each picker the order whose tote is nearest ahead on the lanes).
    assert first.startswith("PickAction tote_A1_2 at (4.5, 3.2)"), first
    assert first.endswith("order 2: tote_A1_2 to station_1"), first
    assert any(r["text"] == "carrying tote_A1_2" for r in shots.timeline)
    assert any(r["text"] == "order 2: tote_A1_2 to station_1 done" for r in shots.timeline)
    assert len(shots.files) == len(MOMENTS) == 3
    for path in shots.files:
        assert path.stat().st_size > 10_000
    assert shots.doing[0].startswith("now moving: PickAction tote_A1_2")
    assert shots.doing[1].startswith("now carrying: MoveAction at (6.5, 14.6)")
    assert shots.doing[2].startswith("now carrying: DropAction tote_A1_2")
