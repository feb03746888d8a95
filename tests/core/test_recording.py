"""Recording to GIF / MP4: frame timing, auto-stop and auto-save, cameras, errors."""

from __future__ import annotations

import sys

import imageio.v3 as iio
import numpy as np
import pybullet as p
import pytest
from PIL import Image

from fleet_async import (
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    SimulationRecorder,
)

SMALL = {"width": 64, "height": 48}
RED = ShapeParams("box", half_extents=[0.3, 0.3, 0.3], rgba_color=[1.0, 0.0, 0.0, 1.0])


def red_box(sim, x=0.0, y=0.0):
    return SimObject.from_mesh(
        visual_shape=RED, collision_shape=RED, pose=Pose.from_xyz(x, y, 0.3), sim_core=sim
    )


def moving_red_box(sim):
    """A red box that moves 10 cm every step, so that no two steps render alike."""
    box = red_box(sim)
    sim.register_callback(
        lambda s, dt: box.set_pose(Pose.from_xyz(0.1 * s.step_count + 0.1, 0, 0.3))
    )
    return box


def red_pixels(rgb) -> int:
    rgb = np.asarray(rgb, dtype=int)
    return int(((rgb[..., 0] > 150) & (rgb[..., 1] < 80) & (rgb[..., 2] < 80)).sum())


def gif_frames(path):
    """(frames as RGB arrays, per-frame durations in ms, loop) of a GIF."""
    with Image.open(path) as im:
        frames, durations = [], []
        for i in range(im.n_frames):
            im.seek(i)
            frames.append(np.asarray(im.convert("RGB")))
            durations.append(im.info["duration"])
        return frames, durations, im.info.get("loop")


def steps_of_captures(monkeypatch, sim):
    """Record the step count at which each frame is rendered."""
    steps = []
    real = SimulationRecorder.capture_frame

    def spy(self, frame_index=0):
        steps.append(sim.step_count)
        return real(self, frame_index)

    monkeypatch.setattr(SimulationRecorder, "capture_frame", spy)
    return steps


# ----- frame timing ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("fps", "duration", "frames", "capture_steps"),
    [
        (10, 1.0, 10, list(range(10))),  # one frame per step (dt = 0.1 s)
        (4, 2.0, 8, [0, 3, 5, 8, 10, 13, 15, 18]),  # frame k at the first step >= k / fps
        (15, 1.0, 15, list(range(11))),  # faster than the step rate: frames repeat
    ],
)
def test_gif_holds_one_frame_per_slot_of_sim_time(
    sim, tmp_path, monkeypatch, fps, duration, frames, capture_steps
):
    moving_red_box(sim)
    captured = steps_of_captures(monkeypatch, sim)
    out = tmp_path / "run.gif"
    recorder = sim.start_recording(str(out), fps=fps, duration=duration, **SMALL)
    sim.run_simulation(duration=3.0)

    assert recorder.frame_count == frames
    assert captured == capture_steps
    images, durations, loop = gif_frames(out)
    assert len(images) == len(capture_steps)  # repeated frames become longer GIF frames
    assert images[0].shape == (48, 64, 3)
    assert sum(durations) == round(1000 * duration)  # 1x playback, exact to the centisecond
    assert loop == 0


def test_duration_stops_and_saves_at_the_step_that_reaches_it(sim, tmp_path):
    out = tmp_path / "stop.gif"
    recorder = sim.start_recording(str(out), fps=5, duration=0.7, **SMALL)
    assert sim.events.handler_count(SimEvents.POST_STEP) == 1
    for _ in range(6):
        sim.step_once()
    assert recorder.is_recording
    assert not out.exists()
    sim.step_once()  # step 7: sim time 0.7 s
    assert not recorder.is_recording
    assert out.exists()
    assert recorder.frame_count == 4  # ceil(0.7 s * 5 fps): slots at 0, 0.2, 0.4, 0.6 s
    assert sim.events.handler_count(SimEvents.POST_STEP) == 0
    assert sim.stop_recording() is None  # it already stopped by itself


def test_run_simulation_saves_a_recording_still_running(sim, tmp_path):
    out = tmp_path / "nested" / "dir" / "run.gif"
    recorder = sim.start_recording(out, fps=10, **SMALL)
    assert out.parent.is_dir()
    sim.run_simulation(duration=0.5)
    assert not recorder.is_recording
    assert recorder.frame_count == 6  # slots at 0.0 .. 0.5 s
    with Image.open(out) as im:
        assert im.size == (64, 48)
    assert sim.stop_recording() is None


def test_stop_recording_returns_the_path_and_a_new_recording_may_start(sim, tmp_path):
    assert sim.stop_recording() is None
    first = tmp_path / "a.gif"
    sim.start_recording(first, **SMALL)
    with pytest.raises(RuntimeError, match=r"a\.gif.*already running.*stop_recording"):
        sim.start_recording(tmp_path / "b.gif", **SMALL)
    sim.step_once()
    assert sim.stop_recording() == str(first)
    assert first.exists()
    second = sim.start_recording(tmp_path / "b.gif", **SMALL)
    assert second.is_recording
    assert sim.stop_recording() == str(tmp_path / "b.gif")


def test_real_time_base_fills_every_wall_clock_slot(sim, tmp_path):
    moving_red_box(sim)
    now = [100.0]
    out = tmp_path / "real.gif"
    recorder = sim.start_recording(
        out, fps=10, duration=0.5, time_base="real", clock=lambda: now[0], **SMALL
    )
    for wall, frames in [(0.05, 1), (0.1, 2), (0.35, 4), (0.45, 5)]:
        now[0] = 100.0 + wall
        sim.step_once()
        assert recorder.frame_count == frames
    assert recorder.is_recording
    now[0] = 100.6
    sim.step_once()  # past the wall duration: stopped, no slot beyond 0.5 s
    assert not recorder.is_recording
    assert recorder.frame_count == 5
    _, durations, _ = gif_frames(out)
    assert durations == [100, 100, 200, 100]  # 0.25 .. 0.35 s ran in one step: held twice


def test_mp4_is_written_and_reads_back(sim, tmp_path):
    moving_red_box(sim)
    out = tmp_path / "video" / "run.mp4"
    recorder = sim.start_recording(out, fps=10, duration=1.0, **SMALL)
    sim.run_simulation(duration=2.0)
    assert recorder.frame_count == 10
    frames = iio.imread(out, plugin="pyav")
    assert frames.shape == (10, 48, 64, 3)
    assert iio.immeta(out, plugin="pyav")["fps"] == 10.0
    assert red_pixels(frames[0]) > 0


# ----- what the frames show ----------------------------------------------------------------


def test_frames_show_the_scene(sim, tmp_path):
    sim.start_recording(tmp_path / "empty.gif", **SMALL)
    assert sim.stop_recording() is not None
    red_box(sim)
    sim.start_recording(tmp_path / "box.gif", **SMALL)
    sim.stop_recording()
    assert red_pixels(gif_frames(tmp_path / "empty.gif")[0][0]) == 0
    assert red_pixels(gif_frames(tmp_path / "box.gif")[0][0]) > 20


def test_frames_follow_kinematic_poses_set_in_the_store(sim, tmp_path):
    box = red_box(sim)
    recorder = sim.start_recording(
        tmp_path / "m.gif", camera_mode="manual", camera_params={"distance": 3.0}, **SMALL
    )
    # Auto framing targeted the box; moving it far away must empty the frame.
    assert red_pixels(recorder.capture_frame()) > 20
    box.set_pose(Pose.from_xyz(50.0, 50.0, 0.3))
    assert red_pixels(recorder.capture_frame()) == 0
    sim.stop_recording()


def test_auto_camera_frames_the_scene_where_it_is(sim, tmp_path):
    red_box(sim, 20.0, 20.0)
    red_box(sim, 22.0, 20.0)
    auto = sim.start_recording(tmp_path / "auto.gif", **SMALL)
    assert auto.camera_mode == "auto"
    assert auto.camera_view()[3] == pytest.approx([21.0, 20.0, 0.3])
    assert red_pixels(auto.capture_frame()) > 20
    sim.stop_recording()
    manual = sim.start_recording(
        tmp_path / "origin.gif",
        camera_mode="manual",
        camera_params={"distance": 3.0, "yaw": 10.0, "pitch": -30.0, "target": [0, 0, 0]},
        **SMALL,
    )
    assert manual.camera_view() == (3.0, 10.0, -30.0, [0.0, 0.0, 0.0])
    assert red_pixels(manual.capture_frame()) == 0
    sim.stop_recording()


def test_orbit_turns_the_yaw_over_the_duration(sim, tmp_path):
    red_box(sim, 1.0, 0.0)
    red_box(sim, -1.0, 0.0)
    out = tmp_path / "orbit.gif"
    recorder = sim.start_recording(
        out, fps=10, duration=1.0, camera_mode="orbit", orbit_degrees=90, **SMALL
    )
    yaw0 = recorder.camera_view(0)[1]
    assert [recorder.camera_view(k)[1] - yaw0 for k in range(3)] == [0.0, 9.0, 18.0]
    sim.run_simulation(duration=1.0)
    images, _, _ = gif_frames(out)
    assert len(images) == 10  # a still scene, but every frame differs as the camera turns


def test_orbit_without_duration_turns_a_fixed_step_per_frame(sim, tmp_path):
    recorder = sim.start_recording(tmp_path / "o.gif", camera_mode="orbit", **SMALL)
    assert recorder.camera_view(90)[1] - recorder.camera_view(0)[1] == 90.0  # 360 deg / 360
    sim.stop_recording()


def test_still_camera_on_a_still_scene_merges_into_one_gif_frame(sim, tmp_path):
    red_box(sim)
    out = tmp_path / "still.gif"
    sim.start_recording(out, fps=10, duration=1.0, **SMALL)
    sim.run_simulation(duration=1.0)
    images, durations, _ = gif_frames(out)
    assert (len(images), durations) == (1, [1000])  # Pillow merges identical frames


def test_gui_camera_mode_needs_a_gui(sim, tmp_path):
    with pytest.raises(ValueError, match="camera_mode: 'gui' needs a GUI"):
        sim.start_recording(tmp_path / "g.gif", camera_mode="gui", **SMALL)


def test_auto_becomes_gui_and_follows_the_gui_camera(sim, tmp_path, monkeypatch):
    red_box(sim, 5.0, 5.0)
    monkeypatch.setattr(MultiRobotSimulationCore, "is_gui", property(lambda self: True))
    camera = [(0, 0, (), (), (), (), (), (), 30.0, -40.0, 4.0, (5.0, 5.0, 0.0))]
    monkeypatch.setattr(p, "getDebugVisualizerCamera", lambda physicsClientId: camera[0])
    recorder = sim.start_recording(tmp_path / "g.gif", **SMALL)
    assert recorder.camera_mode == "gui"
    assert recorder.camera_view() == (4.0, 30.0, -40.0, [5.0, 5.0, 0.0])
    assert red_pixels(recorder.capture_frame()) > 20
    camera[0] = (0, 0, (), (), (), (), (), (), 30.0, -40.0, 4.0, (-20.0, 0.0, 0.0))
    assert red_pixels(recorder.capture_frame()) == 0  # the user turned the GUI camera away
    sim.stop_recording()


# ----- errors ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"camera_mode": "fisheye"}, "camera_mode.*'fisheye'"),
        ({"time_base": "wall"}, "time_base.*'wall'"),
        ({"output": "x.avi"}, r"extension '\.avi'.*x\.avi"),
        ({"output": "noext"}, "extension ''"),
        ({"fps": 0}, "fps.*got 0"),
        ({"fps": 2.5}, "fps.*got 2.5"),
        ({"width": 0}, "width.*got 0"),
        ({"height": -5}, "height.*got -5"),
        ({"duration": 0}, "duration.*got 0"),
        ({"duration": -1.0}, r"duration.*got -1\.0"),
        ({"fps": 60}, "fps: 60 is too high for a GIF"),
        ({"output": "x.mp4", "width": 65}, "width.*even.*65"),
        ({"camera_mode": "manual"}, "camera_params: required by camera_mode='manual'"),
        ({"camera_params": {"distance": 2.0}}, "camera_params.*camera_mode='auto'"),
        (
            {"camera_mode": "manual", "camera_params": {"zoom": 2, "yaw": 0}},
            r"unknown key\(s\) \['zoom'\]",
        ),
        (
            {"camera_mode": "manual", "camera_params": {"distance": -1.0}},
            r"camera_params.distance.*-1\.0",
        ),
        ({"camera_mode": "manual", "camera_params": {"target": [0, 0]}}, r"target.*\[0, 0\]"),
        ({"orbit_degrees": 90}, "orbit_degrees: applies to camera_mode='orbit'"),
        ({"camera_mode": "orbit", "orbit_degrees": "lots"}, "orbit_degrees.*'lots'"),
    ],
)
def test_bad_arguments_name_the_parameter_and_value(sim, tmp_path, kwargs, message):
    kwargs = {"output": "x.gif", **kwargs}
    kwargs["output"] = tmp_path / kwargs["output"]
    with pytest.raises(ValueError, match=message):
        sim.start_recording(**kwargs)
    assert sim.events.handler_count(SimEvents.POST_STEP) == 0
    assert list(tmp_path.iterdir()) == []


def test_unknown_keyword_arguments_are_named(sim, tmp_path):
    with pytest.raises(TypeError, match=r"\['fov', 'zoom'\].*orbit_degrees"):
        sim.start_recording(tmp_path / "x.gif", zoom=2, fov=60)


@pytest.mark.parametrize(
    ("output", "blocked", "names"),
    [
        ("x.gif", ["PIL", "PIL.Image"], "Pillow"),
        ("x.mp4", ["av"], "imageio with its pyav plugin"),
    ],
)
def test_missing_package_says_what_to_install_before_recording(
    sim, tmp_path, monkeypatch, output, blocked, names
):
    for module in blocked:
        monkeypatch.setitem(sys.modules, module, None)
    with pytest.raises(ImportError, match=names) as info:
        sim.start_recording(tmp_path / output, **SMALL)
    assert 'python -m pip install Pillow "imageio[pyav]"' in str(info.value)
    assert sim.events.handler_count(SimEvents.POST_STEP) == 0
    monkeypatch.undo()
    assert sim.start_recording(tmp_path / output, **SMALL).is_recording  # nothing left running
    sim.stop_recording()
