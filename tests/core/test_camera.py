"""Cameras: camera_config, framing the run, follow / fleet / top-down, the GUI camera."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet as p
import pytest

from fleet_async import (
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimObject,
    SimulationParams,
)
from fleet_async.cli.run import load_scenario
from fleet_async.core.base.camera_config import parse_camera_config, parse_camera_mode
from fleet_async.core.view import gui
from fleet_async.core.view.camera import SceneCamera, fit_distance
from tests.conftest import headless_params

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"
BOX = ShapeParams("box", half_extents=[0.25, 0.25, 0.1], rgba_color=[0.2, 0.4, 0.9, 1.0])


def box(sim, x=0.0, y=0.0, name=None):
    return SimObject.from_mesh(
        visual_shape=BOX,
        collision_shape=BOX,
        pose=Pose.from_xyz(x, y, 0.1),
        sim_core=sim,
        name=name,
    )


def ndc(points, view, fov_deg, aspect):
    """Normalised device coordinates of world points seen by a (distance, yaw, pitch, target)."""
    distance, yaw, pitch, target = view
    v = np.asarray(p.computeViewMatrixFromYawPitchRoll(target, distance, yaw, pitch, 0, 2))
    proj = p.computeProjectionMatrixFOV(fov_deg, aspect, distance * 0.01, distance * 10 + 10)
    clip = np.c_[np.asarray(points, dtype=float), np.ones(len(points))]
    clip = clip @ v.reshape(4, 4) @ np.asarray(proj).reshape(4, 4)
    return clip[:, :3] / clip[:, 3:4]


def corners(lo, hi):
    return [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]


# ----- camera_config --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"camera_mode": "fisheye"}, r"camera_config.camera_mode: expected one of .*'fisheye'"),
        ({"camera_mode": "follow:"}, r"camera_mode: .*got 'follow:'"),
        ({"camera_zoom": 2}, r"unknown key\(s\) \['camera_zoom'\]"),
        ({"camera_view_type": "iso"}, r"camera_view_type: .*'iso'"),
        ({"camera_auto_scale": 0}, r"camera_auto_scale: expected a number > 0, got 0"),
        ({"camera_yaw": "north"}, r"camera_yaw: expected a number, got 'north'"),
        ({"camera_target": [1, 2]}, r"camera_target: expected \[x, y, z\].*\[1, 2\]"),
    ],
)
def test_bad_camera_config_names_the_key_and_value(config, message):
    with pytest.raises(ValueError, match=message):
        SimulationParams(gui=False, camera_config=config)


def test_a_bad_camera_config_in_a_file_names_the_file(tmp_path):
    path = tmp_path / "cam.yaml"
    path.write_text("simulation:\n  gui: false\n  camera_config: {camera_mode: fisheye}\n")
    with pytest.raises(ValueError, match=r"cam\.yaml.*camera_mode.*'fisheye'"):
        MultiRobotSimulationCore.from_yaml(path)


def test_camera_modes_parse():
    assert parse_camera_mode("follow: robot 7") == ("follow", "robot 7")
    assert parse_camera_mode("top-down") == ("top_down", None)
    config = parse_camera_config({"camera_view_type": "top_down", "camera_auto_scale": 1.2})
    assert (config.mode, config.top_down, config.label, config.view_pitch) == (
        "auto",
        True,
        "top_down",
        -89.9,
    )
    assert config.with_mode("fleet", "x").label == "fleet"
    assert parse_camera_config({"camera_mode": "follow:r1"}).follow == "r1"


# ----- framing --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("yaw", "pitch", "aspect"), [(0, -60, 4 / 3), (0, -89.9, 1.0), (35, -30, 2.0)]
)
def test_fit_distance_puts_every_corner_in_view_and_one_on_the_edge(yaw, pitch, aspect):
    lo, hi = [-3.0, -1.0, 0.0], [5.0, 9.0, 2.0]
    distance = fit_distance(lo, hi, yaw, pitch, 60.0, aspect)
    target = ((np.asarray(lo) + np.asarray(hi)) / 2).tolist()
    seen = np.abs(ndc(corners(lo, hi), (distance, yaw, pitch, target), 60.0, aspect)[:, :2])
    assert seen.max() == pytest.approx(1.0, abs=1e-6)


def test_auto_widens_when_a_body_leaves_and_never_narrows(sim):
    a, b = box(sim, 0, 0), box(sim, 4, 0)
    camera = SceneCamera(sim, sim.params.camera)
    first = camera.view()
    b.set_pose(Pose.from_xyz(14.0, 0.0, 0.1))
    wide = camera.view()
    assert wide[0] > first[0] and wide[3][0] > first[3][0]
    b.set_pose(Pose.from_xyz(4.0, 0.0, 0.1))
    assert camera.view() == wide  # where the run went stays in view
    seen = ndc([a.get_pose().position, [14.0, 0.0, 0.1]], wide, 60.0, 4 / 3)
    assert np.abs(seen[:, :2]).max() < 1.0


def test_fleet_follows_the_agents_and_narrows_slowly():
    scenario = load_scenario(EXAMPLES / "pick_drop.yaml", gui_on=False, rtf=None)
    try:
        camera = SceneCamera(scenario, parse_camera_config({"camera_mode": "fleet"}))
        distances, targets = [], []
        for _ in range(240):
            scenario.step_once()
            view = camera.view()
            distances.append(view[0])
            targets.append(view[3][1])
            for agent in scenario.agents:
                lo, hi = scenario.get_aabb_bounds([agent.object_id])
                assert np.abs(ndc(corners(lo, hi), view, 60.0, 4 / 3)[:, :2]).max() < 1.0
        shrink = np.diff(distances)
        assert (shrink >= -0.03 * np.asarray(distances[:-1]) - 1e-9).all()  # 3% a frame at most
        assert max(targets) - min(targets) > 3.0  # it went with the robots, up and down y
    finally:
        scenario.close()


def test_follow_keeps_the_body_in_the_middle(sim):
    mover = box(sim, 0, 0, name="mover")
    box(sim, 30, 30)
    camera = SceneCamera(sim, parse_camera_config({"camera_mode": "follow:mover"}))
    distance = camera.view()[0]
    mover.set_pose(Pose.from_xyz(7.0, -3.0, 0.1))
    view = camera.view()
    assert view[3] == pytest.approx([7.0, -3.0, 0.1]) and view[0] == distance
    assert distance < 10.0  # close to the body, not framing the far box


def test_follow_of_an_unknown_body_names_it_and_the_bodies(sim):
    box(sim, name="alpha")
    with pytest.raises(ValueError, match=r"follow:ghost: no body called 'ghost'.*alpha"):
        SceneCamera(sim, parse_camera_config({"camera_mode": "follow:ghost"}))


@pytest.mark.parametrize("mode", ["auto", "top_down"])
def test_every_robot_stays_in_the_recording_of_pick_drop(mode, tmp_path):
    sim = load_scenario(EXAMPLES / "pick_drop.yaml", gui_on=False, rtf=None)
    try:
        recorder = sim.start_recording(tmp_path / "r.gif", width=96, height=72, camera_mode=mode)
        for step in range(400):  # the whole run: out to the shelves and back to the lanes
            sim.step_once()
            if step % 5:
                continue
            view = recorder.camera_view(step)
            for agent in sim.agents:
                lo, hi = sim.get_aabb_bounds([agent.object_id])
                assert np.abs(ndc(corners(lo, hi), view, 60.0, 96 / 72)[:, :2]).max() < 1.0
        sim.stop_recording()
    finally:
        sim.close()


def test_recorder_modes_come_from_camera_config_or_the_argument(tmp_path):
    params = headless_params(camera_config={"camera_mode": "top_down", "camera_yaw": 30.0})
    with MultiRobotSimulationCore(params) as sim:
        box(sim, 0, 0, name="r")
        auto = sim.start_recording(tmp_path / "a.gif", width=64, height=48)
        assert auto.camera_view()[1:3] == (30.0, -89.9)
        sim.stop_recording()
        follow = sim.start_recording(
            tmp_path / "f.gif", width=64, height=48, camera_mode="follow:r"
        )
        assert follow.camera_view()[3] == pytest.approx([0.0, 0.0, 0.1])
        sim.stop_recording()
        with pytest.raises(
            ValueError, match=r"recording camera_mode: follow:x: no body called 'x'"
        ):
            sim.start_recording(tmp_path / "x.gif", camera_mode="follow:x")


# ----- the GUI camera ---------------------------------------------------------------------------


class FakeGui:
    """Stands in for PyBullet's debug visualizer camera (no display in the tests)."""

    def __init__(self, monkeypatch):
        self.resets = []
        proj = list(p.computeProjectionMatrixFOV(50.0, 1.5, 0.1, 100.0))
        self.camera = (800, 600, [0.0] * 16, proj, 0, 0, 0, 0, 50.0, -35.0, 5.0, (0.0, 0.0, 0.0))
        monkeypatch.setattr(MultiRobotSimulationCore, "is_gui", property(lambda self: True))
        monkeypatch.setattr(p, "getDebugVisualizerCamera", lambda physicsClientId: self.camera)
        monkeypatch.setattr(p, "resetDebugVisualizerCamera", self.reset)
        monkeypatch.setattr(p, "configureDebugVisualizer", lambda *a, **k: None)

    def reset(self, distance, yaw, pitch, target, physicsClientId):
        self.resets.append((distance, yaw, pitch, list(target)))


def test_gui_projection_reads_the_window_camera(monkeypatch):
    FakeGui(monkeypatch)
    fov, aspect = gui.gui_projection(0)
    assert fov == pytest.approx(50.0) and aspect == pytest.approx(1.5)


def test_the_gui_opens_framed_on_the_scene_and_widens_with_the_run(monkeypatch):
    fake = FakeGui(monkeypatch)
    with MultiRobotSimulationCore(headless_params()) as sim:
        a, b = box(sim, 0, 0), box(sim, 3, 0)
        sim.step_once()  # the first step frames the window
        assert len(fake.resets) == 1
        distance, _, pitch, _ = fake.resets[0]
        seen = ndc([a.get_pose().position, b.get_pose().position], fake.resets[0], 50.0, 1.5)
        assert np.abs(seen[:, :2]).max() < 1.0 and pitch == -60.0
        sim.step_once()
        assert len(fake.resets) == 1  # nothing moved: the camera is not touched
        b.set_pose(Pose.from_xyz(20.0, 5.0, 0.1))
        sim.step_once()
        assert len(fake.resets) == 2 and fake.resets[1][0] > distance
        sim.reset()
        box(sim, 50, 50)
        sim.step_once()
        assert fake.resets[-1][3][:2] == pytest.approx([50.0, 50.0])


def test_the_gui_follows_a_body_and_orbits(monkeypatch):
    fake = FakeGui(monkeypatch)
    params = headless_params(camera_config={"camera_mode": "follow:mover"})
    with MultiRobotSimulationCore(params) as sim:
        mover = box(sim, 0, 0, name="mover")
        sim.step_once()
        mover.set_pose(Pose.from_xyz(2.0, 1.0, 0.1))
        sim.step_once()
        assert fake.resets[-1][3] == pytest.approx([2.0, 1.0, 0.1])
        sim.params.camera_config = {"camera_mode": "orbit"}
        sim.reset()
        box(sim)
        for _ in range(11):
            sim.step_once()
        yaws = [reset[1] for reset in fake.resets[-2:]]
        assert yaws[1] - yaws[0] == pytest.approx(gui.ORBIT_DEGREES_PER_SECOND * 0.1)


def test_setup_camera_applies_the_view_to_the_gui(monkeypatch):
    fake = FakeGui(monkeypatch)
    with MultiRobotSimulationCore(headless_params()) as sim:
        box(sim, 1, 1)
        view = sim.setup_camera({"camera_mode": "manual", "camera_distance": 7.0})
        assert view == (7.0, 0.0, -45.0, [0.0, 0.0, 0.0]) and fake.resets == [view]
        assert math.isclose(sim.setup_camera({"camera_mode": "top_down"})[2], -89.9)
