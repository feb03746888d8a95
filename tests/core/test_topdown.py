"""The top-down recording renderer: every body drawn where the state store says, carried
loads over their robots, robots never below the set size, frames = duration x fps."""

from __future__ import annotations

import numpy as np
import pytest

from fleet_async import (
    Agent,
    PickAction,
    Pose,
    ShapeParams,
    SimObject,
)
from fleet_async.core.view.topdown import TopDownRenderer

RED = ShapeParams("box", half_extents=[0.3, 0.3, 0.1], rgba_color=[1.0, 0.0, 0.0, 1.0])
GREEN = ShapeParams("box", half_extents=[0.1, 0.1, 0.05], rgba_color=[0.0, 1.0, 0.0, 1.0])
BLUE = ShapeParams("box", half_extents=[1.0, 0.2, 0.5], rgba_color=[0.0, 0.0, 1.0, 1.0])


def pixel_of(renderer, x, y):
    cx, cy, scale = renderer.view()
    return int(renderer_width(renderer) / 2 + (x - cx) * scale), int(
        renderer_height(renderer) / 2 - (y - cy) * scale
    )


def renderer_width(renderer):
    return renderer.frame().shape[1]


def renderer_height(renderer):
    return renderer.frame().shape[0]


@pytest.fixture
def scene(sim):
    robot = Agent.from_mesh(RED, RED, Pose.from_xyz(0, 0, 0.1), sim_core=sim, name="robot")
    tote = SimObject.from_mesh(
        GREEN, GREEN, Pose.from_xyz(2, 0, 0.05), sim_core=sim, name="tote", pickable=True
    )
    rack = SimObject.from_mesh(
        BLUE, BLUE, Pose.from_xyz(0, 3, 0.5), sim_core=sim, name="rack", collision_mode="static"
    )
    return robot, tote, rack


def test_every_body_is_drawn_in_its_colour_where_it_is(sim, scene):
    renderer = TopDownRenderer(sim, 400, 300)
    image = renderer.frame()
    for x, y, rgb in ((-0.15, 0.15, (255, 0, 0)), (2.0, 0.0, (0, 255, 0)), (0.5, 3.0, (0, 0, 255))):
        col, row = pixel_of(renderer, x, y)
        assert tuple(image[row, col]) == rgb, (x, y)


def test_a_carried_load_is_drawn_over_its_robot_and_the_view_widens(sim, scene):
    robot, tote, _ = scene
    renderer = TopDownRenderer(sim, 400, 300)
    renderer.frame()
    first = renderer.view()
    robot.add_action(PickAction(target_object_id=tote, approach_offset=0.5))
    for _ in range(100):
        sim.step_once()
    assert tote.is_attached()
    image = renderer.frame()
    pose = tote.get_pose()
    col, row = pixel_of(renderer, float(pose.x), float(pose.y))
    assert tuple(image[row, col]) == (0, 255, 0)
    robot.set_pose(Pose.from_xyz(12.0, 0.0, 0.1))
    renderer.frame()
    assert renderer.view()[2] < first[2]  # wider: smaller scale
    robot.set_pose(Pose.from_xyz(6.0, 0.0, 0.1))  # inside what was seen
    before = renderer.view()
    renderer.frame()
    assert renderer.view() == before  # never narrows


def test_robots_never_shrink_below_the_set_size(sim, scene):
    Agent.from_mesh(RED, RED, Pose.from_xyz(2, 2, 0.1), sim_core=sim, name="near")
    Agent.from_mesh(RED, RED, Pose.from_xyz(500, 0, 0.1), sim_core=sim, name="far")
    renderer = TopDownRenderer(sim, 400, 300, min_robot_px=12)
    image = renderer.frame()
    cx, cy, scale = renderer.view()
    assert scale * 0.6 == pytest.approx(12)  # a 0.6 m robot, 12 px across
    assert (cx, cy) == (2.0, 0.0)  # around the robots' median position
    col, row = pixel_of(renderer, 1.85, 2.15)
    assert tuple(image[row, col]) == (255, 0, 0)  # "near" is in view, at size


def test_recording_with_the_topdown_renderer_has_duration_times_fps_frames(sim, scene, tmp_path):
    recorder = sim.start_recording(
        tmp_path / "r.mp4", width=160, height=120, fps=15, duration=2.0, renderer="topdown"
    )
    for _ in range(30):
        sim.step_once()
    assert recorder.frame_count == 30  # 2 s x 15 fps
    import imageio.v3 as iio

    frames = iio.imread(tmp_path / "r.mp4", plugin="pyav")
    assert frames.shape == (30, 120, 160, 3)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"renderer": "opengl"}, "recording renderer: expected one of"),
        (
            {"renderer": "topdown", "camera_mode": "orbit"},
            "camera_mode 'orbit' is not a view from above",
        ),
    ],
)
def test_bad_renderer_arguments_are_named(sim, tmp_path, kwargs, message):
    with pytest.raises(ValueError, match=message):
        sim.start_recording(tmp_path / "r.gif", width=64, height=48, **kwargs)


def test_scenario_bodies_all_appear(tmp_path):
    # Every body of the warehouse: 9 racks, 2 stations, 12 totes, the pallet and 9 robots.
    from fleet_async.cli.run import load_scenario
    from tests.test_cli import REPO

    sim = load_scenario(REPO / "examples" / "scenarios" / "warehouse.yaml", False, 0.0)
    try:
        renderer = TopDownRenderer(sim, 800, 600)
        image = renderer.frame()
        cx, cy, scale = renderer.view()
        seen = 0
        for obj in sim.sim_objects:
            pose = obj.get_pose()
            col = int(400 + (float(pose.x) - cx) * scale)
            row = int(300 - (float(pose.y) - cy) * scale)
            if 0 <= col < 800 and 0 <= row < 600:
                seen += 1
                assert not np.array_equal(image[row, col], [244, 246, 248]), obj.name
        assert seen == len(sim.sim_objects)
    finally:
        sim.close()
