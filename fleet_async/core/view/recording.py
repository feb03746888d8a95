"""Recording the simulation to an animated GIF or an MP4 video.

A :class:`SimulationRecorder` renders frames with PyBullet's software renderer
(``ER_TINY_RENDERER``), so it works headless (``p.DIRECT``) as well as with a GUI. It hooks
into the step loop through the ``post_step`` event and never adds branches to ``step_once``.

Frame timing is measured in *slots* of ``1 / fps`` seconds, slot ``k`` starting at
``k / fps`` after the recording started:

* ``time_base="sim"``: slots are sim seconds. After ``n`` steps every slot with
  ``k / fps <= n * timestep`` is due, computed from the integer step count each time (no float
  accumulation), so playback runs at 1x sim speed. When ``fps`` exceeds the step rate a frame
  fills several slots.
* ``time_base="real"``: slots are wall seconds, checked after each step; a frame fills every
  slot that passed since the previous one, so playback shows the actual execution speed.

Slot 0 is captured when the recording starts. With a ``duration`` the recording holds
``ceil(duration * fps)`` slots and stops (and saves) by itself at the first step at or past
``duration``.

The optional packages (Pillow for GIF, imageio with PyAV for MP4) are checked when the
recorder is created, not when a long run ends.
"""

from __future__ import annotations

import logging
import math
import numbers
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, cast

import numpy as np
import pybullet as p

from fleet_async.core.base.camera_config import CAMERA_MODES as CONFIG_CAMERA_MODES
from fleet_async.core.base.events import EventBus, SimEvents
from fleet_async.core.base.steps import steps_for
from fleet_async.core.view.camera import (
    DEFAULT_FOV_DEG,
    CameraSim,
    CameraView,
    SceneCamera,
    parse_camera_params,
)
from fleet_async.core.view.topdown import topdown_for
from fleet_async.core.view.video_writers import WRITERS as _WRITERS

if TYPE_CHECKING:
    from fleet_async.core.base.params import SimulationParams

__all__ = ["CAMERA_MODES", "TIME_BASES", "RecordableSim", "RecordingApi", "SimulationRecorder"]

logger = logging.getLogger(__name__)

CAMERA_MODES = ("auto", "gui", *CONFIG_CAMERA_MODES[1:])
"""Recorder camera modes: ``auto`` (the simulation's ``camera_config``; the GUI's camera when
there is a GUI), ``gui`` and the ``camera_config`` modes (``base/camera_config.py``)."""
TIME_BASES = ("sim", "real")
GIF_MAX_FPS = 50
"""GIF delays are whole 1/100 s and players slow down delays under 2/100 s."""
ORBIT_FRAMES_WITHOUT_DURATION = 360
"""Without a duration, an orbit turns ``orbit_degrees`` every this many frames."""

_EPS = 1e-9  # absorbs float error in products such as 3 * 0.1 * 10


class RecordableSim(CameraSim, Protocol):
    """What a recorder needs from the simulation."""

    @property
    def client(self) -> int: ...
    @property
    def is_gui(self) -> bool: ...
    @property
    def params(self) -> SimulationParams: ...
    @property
    def events(self) -> EventBus: ...
    def sync_pybullet(self) -> int: ...


# ----- argument checks ---------------------------------------------------------------------


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _positive_int(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or int(value) <= 0:
        raise ValueError(f"recording {name}: expected a positive integer, got {value!r}")
    return int(value)


# ----- the recorder ------------------------------------------------------------------------


class SimulationRecorder:
    """Renders the simulation at a fixed frame rate and saves it as a GIF or MP4.

    Args:
        sim: The simulation to record.
        output: Output file; the extension picks the format (``.gif`` or ``.mp4``).
        width: Frame width in pixels (even for ``.mp4``).
        height: Frame height in pixels (even for ``.mp4``).
        fps: Frames per second of the recording, for capture and playback (<= 50 for GIF).
        duration: Length of the recording: sim seconds (``time_base="sim"``) or wall seconds
            (``"real"``); None records until :meth:`stop`.
        camera_mode: ``"auto"`` uses the simulation's ``camera_config`` (by default: every
            body's extent seen so far in the run, so the view widens when a robot drives out
            of it), and becomes ``"gui"`` when the simulation has a GUI; ``"gui"`` follows the
            GUI's camera; ``"top_down"``, ``"orbit"`` (the auto view with the yaw turning),
            ``"fleet"`` (the agents' extent now) and ``"follow:NAME"`` are
            ``camera_config``'s modes with its other keys (``base/camera_config.py``);
            ``"manual"`` uses ``camera_params``.
        time_base: ``"sim"`` or ``"real"``: the clock ``fps`` and ``duration`` refer to.
        orbit_degrees: ``"orbit"`` only: degrees the camera turns over ``duration``, or every
            :data:`ORBIT_FRAMES_WITHOUT_DURATION` frames when there is no duration
            (default 360).
        camera_params: ``"manual"`` only (and required there): ``distance`` (m), ``yaw`` and
            ``pitch`` (degrees), ``target`` ([x, y, z] m). Keys left out take the auto view's
            value.
        clock: Wall clock in seconds for ``time_base="real"`` (injectable for tests).
        renderer: ``"pybullet"`` (its software renderer, any camera) or ``"topdown"`` (a
            footprint drawing of every body seen from above, many times faster:
            ``topdown.py``; camera modes ``auto``, ``top_down`` and ``fleet``).

    Raises:
        ValueError: for a bad argument, naming it and its value.
        ImportError: when the package the format needs is missing, with the install command.
    """

    def __init__(
        self,
        sim: RecordableSim,
        output: str | os.PathLike[str] = "recording.gif",
        width: int = 800,
        height: int = 600,
        fps: int = 15,
        duration: float | None = None,
        camera_mode: str = "auto",
        time_base: str = "sim",
        *,
        orbit_degrees: float | None = None,
        camera_params: dict[str, Any] | None = None,
        clock: Callable[[], float] = time.perf_counter,
        renderer: str = "pybullet",
    ) -> None:
        self._sim = sim
        self._path = Path(output)
        self._width = _positive_int("width", width)
        self._height = _positive_int("height", height)
        self._fps = _positive_int("fps", fps)
        self._check_format()
        if duration is not None and not (_is_number(duration) and duration > 0):
            raise ValueError(
                f"recording duration: expected a number > 0 (s) or None, got {duration!r}"
            )
        if time_base not in TIME_BASES:
            raise ValueError(
                f"recording time_base: expected one of {TIME_BASES}, got {time_base!r}"
            )
        self._duration = None if duration is None else float(duration)
        self._time_base = time_base
        self._total_slots = (
            None if duration is None else math.ceil(float(duration) * self._fps - _EPS)
        )
        self._camera_mode = self._resolve_camera_mode(camera_mode, orbit_degrees, camera_params)
        self._orbit_degrees = 360.0 if orbit_degrees is None else float(orbit_degrees)
        self._camera_params = {} if camera_params is None else parse_camera_params(camera_params)
        self._camera = self._make_camera(camera_mode)
        self._topdown = topdown_for(sim, renderer, camera_mode, self._width, self._height)
        self._clock = clock
        self._writer = _WRITERS[self._path.suffix.lower()](self._path, self._fps)
        self._manual_view: CameraView | None = None
        self._recording = False
        self._stopped = False
        self._slots = 0  # slots written so far
        self._steps = 0  # post_step events seen since start
        self._wall0 = 0.0

    def _check_format(self) -> None:
        suffix = self._path.suffix.lower()
        if suffix not in _WRITERS:
            raise ValueError(
                f"recording output: unsupported file extension {self._path.suffix!r} "
                f"in {str(self._path)!r}; use one of {sorted(_WRITERS)}"
            )
        if suffix == ".gif" and self._fps > GIF_MAX_FPS:
            raise ValueError(
                f"recording fps: {self._fps} is too high for a GIF (at most {GIF_MAX_FPS}); "
                "lower fps or record an .mp4"
            )
        if suffix == ".mp4":
            for name, value in (("width", self._width), ("height", self._height)):
                if value % 2:
                    raise ValueError(f"recording {name}: H.264 MP4 needs an even size, got {value}")

    def _resolve_camera_mode(self, mode: Any, orbit_degrees: Any, camera_params: Any) -> str:
        if not isinstance(mode, str) or not (
            mode in CAMERA_MODES or (mode.startswith("follow:") and mode[7:].strip())
        ):
            raise ValueError(
                f"recording camera_mode: expected one of {CAMERA_MODES} "
                f"(follow:NAME names a body), got {mode!r}"
            )
        if orbit_degrees is not None:
            if mode != "orbit":
                raise ValueError(
                    f"recording orbit_degrees: applies to camera_mode='orbit', not {mode!r}"
                )
            if not _is_number(orbit_degrees):
                raise ValueError(
                    f"recording orbit_degrees: expected a number, got {orbit_degrees!r}"
                )
        if (camera_params is not None) != (mode == "manual"):
            raise ValueError(
                "recording camera_params: required by camera_mode='manual' and only used there "
                f"(camera_mode={mode!r}, camera_params={camera_params!r})"
            )
        if mode == "auto" and self._sim.is_gui:
            return "gui"
        if mode == "gui" and not self._sim.is_gui:
            raise ValueError(
                "recording camera_mode: 'gui' needs a GUI, but the simulation has none"
            )
        return str(mode)

    def _make_camera(self, requested: str) -> SceneCamera | None:
        """The recording's scene camera: ``camera_config``'s, with the requested mode."""
        if self._camera_mode == "gui":
            return None
        config = self._sim.params.camera
        where = "SimulationParams.camera_config"
        if requested == "manual":  # camera_params over the auto view
            config, where = config.with_mode("auto", "recording camera_mode"), "recording"
        elif requested != "auto":
            config, where = config.with_mode(requested, "recording camera_mode"), "recording"
        return SceneCamera(
            self._sim,
            config,
            fov_deg=DEFAULT_FOV_DEG,
            aspect=self._width / self._height,
            where=f"{where} camera_mode",
        )

    # ----- read-only state ------------------------------------------------------------------

    @property
    def output(self) -> str:
        """The output file path."""
        return str(self._path)

    @property
    def camera_mode(self) -> str:
        """The camera mode in effect ("auto" becomes "gui" with a GUI)."""
        return self._camera_mode

    @property
    def time_base(self) -> str:
        """``"sim"`` or ``"real"``."""
        return self._time_base

    @property
    def fps(self) -> int:
        """Frames per second."""
        return self._fps

    @property
    def duration(self) -> float | None:
        """Recording length in seconds of the time base, or None."""
        return self._duration

    @property
    def is_recording(self) -> bool:
        """Whether frames are being captured (between :meth:`start` and :meth:`stop`)."""
        return self._recording

    @property
    def frame_count(self) -> int:
        """Frames recorded so far (slots of ``1 / fps`` s; an MP4 holds exactly this many)."""
        return self._slots

    # ----- camera and frames ----------------------------------------------------------------

    def camera_view(self, frame_index: int = 0) -> CameraView:
        """(distance m, yaw deg, pitch deg, target m) of the camera for frame ``frame_index``.

        Framed modes widen with what they have seen so far, so each call may widen the view.
        """
        if self._camera is None:  # "gui": whatever the window shows
            cam = p.getDebugVisualizerCamera(physicsClientId=self._sim.client)
            return float(cam[10]), float(cam[8]), float(cam[9]), [float(v) for v in cam[11]]
        if self._camera_params:
            return self._manual(self._camera)
        turn = 0.0
        if self._camera.config.mode == "orbit":
            per_frame = (
                self._orbit_degrees / self._total_slots
                if self._total_slots is not None
                else self._orbit_degrees / ORBIT_FRAMES_WITHOUT_DURATION
            )
            turn = per_frame * frame_index
        return self._camera.view(turn)

    def _manual(self, camera: SceneCamera) -> CameraView:
        """``camera_params``, keys left out from the auto view when the recording started."""
        if self._manual_view is None:
            distance, yaw, pitch, target = camera.view()
            cp = self._camera_params
            self._manual_view = (
                float(cp.get("distance", distance)),
                float(cp.get("yaw", yaw)),
                float(cp.get("pitch", pitch)),
                [float(v) for v in cp.get("target", target)],
            )
        distance, yaw, pitch, target = self._manual_view
        return distance, yaw, pitch, list(target)

    def capture_frame(self, frame_index: int = 0) -> np.ndarray:
        """Render the scene now with frame ``frame_index``'s camera.

        Returns:
            An RGB image, uint8 array of shape (height, width, 3).
        """
        if self._topdown is not None:
            return self._topdown.frame()
        self._sim.sync_pybullet()  # kinematic poses live in the store; PyBullet lags lazily
        distance, yaw, pitch, target = self.camera_view(frame_index)
        view = p.computeViewMatrixFromYawPitchRoll(target, distance, yaw, pitch, 0.0, 2)
        projection = p.computeProjectionMatrixFOV(
            DEFAULT_FOV_DEG, self._width / self._height, distance * 0.01, distance * 10.0 + 10.0
        )
        _, _, rgba, _, _ = p.getCameraImage(
            self._width,
            self._height,
            view,
            projection,
            renderer=p.ER_TINY_RENDERER,
            flags=p.ER_NO_SEGMENTATION_MASK,
            physicsClientId=self._sim.client,
        )
        pixels = np.asarray(rgba, dtype=np.uint8).reshape(self._height, self._width, 4)
        return np.ascontiguousarray(pixels[:, :, :3])

    # ----- start, capture, stop -------------------------------------------------------------

    def start(self) -> None:
        """Create the output's parent directories, capture frame 0 and hook into the loop.

        Raises:
            RuntimeError: if this recorder was already started.
        """
        if self._recording or self._stopped:
            raise RuntimeError(f"SimulationRecorder({self.output!r}) was already started")
        self._path.parent.mkdir(parents=True, exist_ok=True)
        self._manual_view = None
        self._wall0 = self._clock()
        self._write_slots(1)
        # A high number runs late: the frame shows what other post-step handlers did.
        self._sim.events.on(SimEvents.POST_STEP, self._on_post_step, priority=100)
        self._recording = True
        logger.info("recording to %s (%d fps, %s time)", self.output, self._fps, self._time_base)

    def _on_post_step(self, **_: Any) -> None:
        self._steps += 1
        if self._time_base == "sim":
            timestep = self._sim.params.timestep
            due = math.floor(self._steps * self._fps * timestep + _EPS) + 1
            done = self._duration is not None and (
                self._steps >= steps_for(self._duration, timestep)
            )
        else:
            elapsed = self._clock() - self._wall0
            due = math.floor(elapsed * self._fps + _EPS) + 1
            done = self._duration is not None and elapsed >= self._duration
        self._write_slots(due)
        if done:
            self.stop()

    def _write_slots(self, due: int) -> None:
        """Fill slots up to (excluding) ``due`` with the current scene."""
        if self._total_slots is not None:
            due = min(due, self._total_slots)
        if due <= self._slots:
            return
        if self._camera_mode == "orbit":  # each slot has its own yaw
            for k in range(self._slots, due):
                self._writer.add(self.capture_frame(k), 1)
        else:
            self._writer.add(self.capture_frame(self._slots), due - self._slots)
        self._slots = due

    def stop(self) -> str | None:
        """Stop capturing and save the file.

        Returns:
            The output path, or None if the recorder was not recording.
        """
        if not self._recording:
            return None
        self._recording = False
        self._stopped = True
        self._sim.events.off(SimEvents.POST_STEP, self._on_post_step)
        self._writer.close()
        logger.info("saved recording %s (%d frames)", self.output, self._slots)
        return self.output


# ----- the simulation's API ----------------------------------------------------------------

_RECORDER_KWARGS = ("orbit_degrees", "camera_params", "clock", "renderer")


class RecordingApi:
    """``start_recording`` / ``stop_recording`` for MultiRobotSimulationCore."""

    _recorder: SimulationRecorder | None = None

    def start_recording(
        self,
        output: str | os.PathLike[str] = "recording.gif",
        width: int = 800,
        height: int = 600,
        fps: int = 15,
        duration: float | None = None,
        camera_mode: str = "auto",
        time_base: str = "sim",
        **kwargs: Any,
    ) -> SimulationRecorder:
        """Start recording the simulation to an animated GIF or an MP4.

        Frame 0 is captured now; later frames as the simulation steps (see
        :class:`SimulationRecorder` for the arguments). The file is saved by
        :meth:`stop_recording`, when ``duration`` has passed, or when ``run_simulation`` ends.

        Args:
            output: ``.gif`` (needs Pillow) or ``.mp4`` (needs imageio + PyAV) path; parent
                directories are created.
            width: Frame width in pixels.
            height: Frame height in pixels.
            fps: Frames per second, for capture and playback.
            duration: Sim seconds (``time_base="sim"``) or wall seconds (``"real"``); None
                records until :meth:`stop_recording`.
            camera_mode: ``"auto"``, ``"gui"``, ``"top_down"``, ``"orbit"``, ``"fleet"``,
                ``"follow:NAME"`` or ``"manual"``.
            time_base: ``"sim"`` or ``"real"``.
            **kwargs: ``orbit_degrees``, ``camera_params``, ``clock`` or ``renderer``.

        Returns:
            The running recorder.

        Raises:
            RuntimeError: if a recording is already running.
            TypeError: for unknown keyword arguments, naming them.
            ValueError: for bad arguments, naming them and their values.
            ImportError: when the package the format needs is missing.
        """
        running = self._recorder
        if running is not None and running.is_recording:
            raise RuntimeError(
                f"start_recording: a recording to {running.output!r} is already running; "
                "call stop_recording() first"
            )
        unknown = sorted(set(kwargs) - set(_RECORDER_KWARGS))
        if unknown:
            raise TypeError(
                f"start_recording: unknown keyword argument(s) {unknown}; "
                f"valid ones are {list(_RECORDER_KWARGS)}"
            )
        # This mixin is only used by MultiRobotSimulationCore, which is a RecordableSim.
        sim = cast("RecordableSim", self)
        recorder = SimulationRecorder(
            sim, output, width, height, fps, duration, camera_mode, time_base, **kwargs
        )
        recorder.start()
        self._recorder = recorder
        return recorder

    def stop_recording(self) -> str | None:
        """Stop the running recording and save it.

        Returns:
            The saved file's path, or None if nothing was recording.
        """
        recorder, self._recorder = self._recorder, None
        return recorder.stop() if recorder is not None else None

    def _stop_recording_after_run(self) -> None:
        """Called when ``run_simulation`` ends: save a recording still in progress."""
        self.stop_recording()
