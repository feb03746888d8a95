"""The viewer page in real headless Chromium: it draws the trace, plays, selects, reports.

No wall-clock sleeps: the tests drive the clock through the page API (``viewer.seek``) and
wait on page state (``#app``'s data attributes) with playwright's wait functions.
"""

from __future__ import annotations

import math

import pytest

from fleet_async.viewer import TraceReader

READY = "['ready', 'error'].includes(document.getElementById('app').dataset.state)"


def open_trace(page, server, query=""):
    page.goto(server.url + query)
    page.wait_for_function(READY, timeout=60_000)
    state = page.evaluate("viewer.state()")
    assert state["error"] is None, state["error"]
    return state


def frame_at(reader, step):
    return next(f for f in reader.frames() if f.step == step)


def robot_pixel(page, reader, frame, object_id, u=-0.5, v=0.5):
    """Colour at body-frame point (u * half x, v * half y) of a body: inside, off the heading
    bar and off the border."""
    i = frame.ids.tolist().index(object_id)
    shape = reader.shapes[reader.bodies[object_id]["shape"]]
    hx, hy = shape["half"]
    yaw = float(frame.yaw[i])
    lx, ly = u * hx, v * hy
    x = float(frame.position[i][0]) + math.cos(yaw) * lx - math.sin(yaw) * ly
    y = float(frame.position[i][1]) + math.sin(yaw) * lx + math.cos(yaw) * ly
    p = page.evaluate(f"viewer.project({x}, {y})")
    return page.evaluate(f"viewer.pixelAt({p['x']}, {p['y']})"), p


def state_rgb(page, name):
    return [round(c * 255) for c in page.evaluate("viewer.stateColours()")[name]]


def robots(reader):
    return sorted(i for i, b in reader.bodies.items() if b["kind"] == "agent")


@pytest.mark.parametrize("renderer", ["canvas2d", "webgl2"])
def test_robots_are_drawn_where_the_trace_says(browser_page, serve, pick_drop_trace, renderer):
    reader = TraceReader(pick_drop_trace)
    page = browser_page
    state = open_trace(page, serve(pick_drop_trace), f"?renderer={renderer}")
    assert state["renderer"] == renderer and state["frames"] == reader.frame_count == 301
    ids = robots(reader)
    # Step 0: every robot idle at its start; step 200 (20 s): carrying, elsewhere.
    page.evaluate("viewer.seek(0)")
    start = frame_at(reader, 0)
    for object_id in ids:
        rgba, _ = robot_pixel(page, reader, start, object_id)
        assert rgba[:3] == state_rgb(page, "idle") and rgba[3] == 255
    page.evaluate("viewer.seek(20)")
    page.wait_for_function("document.getElementById('app').dataset.step === '200'")
    later = frame_at(reader, 200)
    for object_id in ids:
        i = later.ids.tolist().index(object_id)
        assert later.flags[i] & 2  # the trace says: carrying
        rgba, _ = robot_pixel(page, reader, later, object_id)
        assert rgba[:3] == state_rgb(page, "carrying"), (object_id, rgba)
        # ... and nothing is left where the robot stood at step 0.
        old, _ = robot_pixel(page, reader, start, object_id)
        assert old[3] == 0, (object_id, old)


def test_clock_advances_when_playing(browser_page, serve, pick_drop_trace):
    page = browser_page
    open_trace(page, serve(pick_drop_trace))
    page.evaluate("viewer.seek(0); viewer.setSpeed(10); viewer.play()")
    page.wait_for_function("Number(document.getElementById('app').dataset.simTime) > 2.0")
    page.evaluate("viewer.pause()")
    frame = int(page.get_attribute("#app", "data-frame"))
    assert frame >= 20
    assert page.get_attribute("#app", "data-playing") == "0"
    # The scrub bar follows the clock.
    assert float(page.input_value("#scrub")) == pytest.approx(
        float(page.get_attribute("#app", "data-sim-time")), abs=0.11
    )


def test_click_on_a_robot_selects_it_and_lists_its_actions(browser_page, serve, pick_drop_trace):
    reader = TraceReader(pick_drop_trace)
    page = browser_page
    open_trace(page, serve(pick_drop_trace))
    page.evaluate("viewer.seek(15)")
    target = robots(reader)[1]
    frame = frame_at(reader, 150)
    _, where = robot_pixel(page, reader, frame, target, u=0.0, v=0.0)
    page.mouse.click(where["pageX"], where["pageY"])
    page.wait_for_function(f"document.getElementById('app').dataset.selected === '{target}'")
    name = reader.bodies[target]["name"]
    assert name in page.inner_text("#sel-name")
    # The timeline: each action a span naming its object and goal (completed ones say no
    # status; the pick and the drop here completed).
    events = page.inner_text("#sel-events")
    box = next(
        b["name"] for b in reader.bodies.values() if b.get("pickable") and b["name"] in events
    )
    assert f"PickAction {box} at (" in events and f"DropAction {box} at (" in events
    assert "failed" not in events and "cancelled" not in events
    assert f"carrying {box}" in events
    # Clicking an event seeks the clock to it.
    page.click("#sel-events li >> nth=0")
    page.wait_for_function("Number(document.getElementById('app').dataset.simTime) < 0.5")
    # Clicking empty floor clears the selection.
    stage = page.evaluate("document.getElementById('stage').getBoundingClientRect().toJSON()")
    page.mouse.click(stage["left"] + 5, stage["top"] + 5)
    page.wait_for_function("document.getElementById('app').dataset.selected === ''")


def test_height_filter_hides_bodies_outside_it(browser_page, serve, pick_drop_trace):
    reader = TraceReader(pick_drop_trace)
    page = browser_page
    open_trace(page, serve(pick_drop_trace))
    page.evaluate("viewer.seek(0)")
    frame = frame_at(reader, 0)
    robot = robots(reader)[0]
    assert robot_pixel(page, reader, frame, robot)[0][3] == 255
    page.evaluate("viewer.setZRange(1.0, 3.0)")  # a second storey: the robots are at z 0.15
    assert robot_pixel(page, reader, frame, robot)[0][3] == 0
    page.evaluate("viewer.setZRange(null, null)")
    assert robot_pixel(page, reader, frame, robot)[0][3] == 255


def test_a_cut_trace_shows_its_readable_prefix_and_a_bad_one_an_error(
    browser_page, serve, pick_drop_trace, tmp_path
):
    cut = tmp_path / "cut.fatrace"
    data = pick_drop_trace.read_bytes()
    cut.write_bytes(data[:-20])  # the end record cut short, as a killed run leaves it
    page = browser_page
    page.goto(serve(cut).url)
    page.wait_for_function(READY, timeout=60_000)
    assert page.get_attribute("#app", "data-state") == "ready"
    with pytest.warns(UserWarning, match="readable prefix"):
        expected = TraceReader(cut).frame_count
    assert page.evaluate("viewer.data.frames.length") == expected > 0
    message = page.evaluate("viewer.data.cut")
    assert "cut.fatrace" in message and "truncated" in message and "readable prefix" in message
    bad = bytearray(data)
    bad[24:28] = b"\xff\xff\xff\xff"  # the META record's payload is no longer JSON
    cut.write_bytes(bytes(bad))
    page.goto(serve(cut).url)
    page.wait_for_function(READY, timeout=60_000)
    assert page.get_attribute("#app", "data-state") == "error"
    message = page.inner_text("#error")
    assert "cut.fatrace" in message and "record 0 (META) at byte 16" in message
    assert "versions 1 and 2" in message


def test_stacked_robots_get_a_count_and_devices_are_not_counted_as_robots(
    browser_page, serve, tmp_path
):
    # Three robots on one spot (robots driving through each other to one drop point hide
    # each other from above) and a door: the page says 4 robots, marks the stack "x3", and
    # draws the door as a device, not a robot.
    from fleet_async import (
        Agent,
        AgentSpawnParams,
        Door,
        MultiRobotSimulationCore,
        Pose,
        SimulationParams,
    )
    from fleet_async.core.world.shapes import ShapeParams

    path = tmp_path / "stacked.fatrace"
    cube = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
    params = SimulationParams(gui=False, monitor=False, target_rtf=0.0, enable_floor=False)
    with MultiRobotSimulationCore(params) as sim:
        for x in (0.0, 0.0, 0.0, 2.0):
            Agent.from_params(
                AgentSpawnParams(
                    visual_shape=cube, collision_shape=cube, initial_pose=Pose.from_xyz(x, 0.0, 0.1)
                ),
                sim,
            )
        Door.from_dict({"name": "door", "pose": [1.0, 2.0, 0.0], "open_time": 1.0}, sim)
        sim.start_trace(path)
        for _ in range(3):
            sim.step_once()
    reader = TraceReader(path)
    assert [b.get("device", False) for b in reader.bodies.values() if b["kind"] == "agent"] == [
        False,
        False,
        False,
        False,
        True,
    ]
    page = browser_page
    open_trace(page, serve(path))
    page.evaluate("viewer.seek(0.1)")
    assert " 4 robots" in page.inner_text("#status")
    page.wait_for_function("document.getElementById('app').dataset.stacked === '1'")
    page.evaluate("viewer.setZRange(1.0, 3.0)")  # nobody up there: no stack to mark
    page.wait_for_function("document.getElementById('app').dataset.stacked === '0'")
