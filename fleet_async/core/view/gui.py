"""GUI concerns: visualizer flags, the camera and keyboard shortcuts (no-ops headless).

``GuiApi`` is the simulation's side of it (``setup_camera``, ``configure_visualizer``, ...).
With a GUI, a :class:`GuiCamera` frames the window on the scene when the run starts and keeps
it there per ``camera_config`` (``view/camera.py`` computes the views, as for recordings).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import pybullet as p

from fleet_async.core.base.camera_config import CAMERA_KEYS, parse_camera_config
from fleet_async.core.base.events import SimEvents
from fleet_async.core.view.camera import DEFAULT_FOV_DEG, CameraView, SceneCamera, box_view

if TYPE_CHECKING:
    from fleet_async.core.base.params import SimulationParams
    from fleet_async.core.sim.kernel import SimulationKernel
    from fleet_async.core.world.state import KinematicState

__all__ = [
    "CAMERA_KEYS",
    "ORBIT_DEGREES_PER_SECOND",
    "GuiApi",
    "GuiCamera",
    "configure_visualizer",
    "gui_projection",
    "handle_keyboard",
    "scene_bounds",
]

ORBIT_DEGREES_PER_SECOND = 6.0
"""How fast the GUI's ``orbit`` camera turns: once a minute of sim time."""
_UPDATE_SECONDS = 0.1  # sim seconds between two GUI camera updates


def scene_bounds(positions: np.ndarray) -> tuple[list[float], list[float]]:
    """(center, extent) of a set of positions: mean point and max - min per axis."""
    if len(positions) == 0:
        return [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    center = positions.mean(axis=0)
    extent = positions.max(axis=0) - positions.min(axis=0)
    return center.tolist(), extent.tolist()


def gui_projection(client: int) -> tuple[float, float]:
    """(vertical field of view in degrees, width / height) of the GUI window's camera."""
    proj = p.getDebugVisualizerCamera(physicsClientId=client)[3]
    if not proj or not proj[0] or not proj[5]:
        return DEFAULT_FOV_DEG, 4.0 / 3.0
    return math.degrees(2.0 * math.atan(1.0 / proj[5])), proj[5] / proj[0]


class GuiCamera:
    """Keeps the GUI camera on the scene per ``camera_config``.

    Framed on the first step after it is (re)started, then updated every 0.1 sim seconds, and
    told PyBullet only when the view changed: ``auto`` / ``top_down`` change only when a body
    leaves the view (so a camera moved by hand stays until then), ``fleet`` and ``follow``
    track their bodies, ``orbit`` turns (:data:`ORBIT_DEGREES_PER_SECOND`), ``manual`` stays.
    """

    def __init__(self, sim: SimulationKernel) -> None:
        self._sim = sim
        self._camera: SceneCamera | None = None
        self._shown: tuple[float, ...] | None = None
        self._every = max(1, round(_UPDATE_SECONDS / sim.params.timestep))

    def restart(self) -> None:
        """Frame the scene afresh at the next update (a reset, a new run)."""
        self._camera, self._shown = None, None

    def frame(self) -> CameraView:
        """Frame the window on the scene now; return the view."""
        fov, aspect = gui_projection(self._sim.client)
        self._camera = SceneCamera(self._sim, self._sim.params.camera, fov_deg=fov, aspect=aspect)
        self._shown = None
        return self._show(self._camera.view())

    def on_post_step(self, step: int, sim_time: float, **_: Any) -> None:
        """Per step: frame the first time, then update every few steps."""
        if self._camera is None:
            self.frame()
        elif step % self._every == 0:
            turn = ORBIT_DEGREES_PER_SECOND * sim_time
            self._show(self._camera.view(turn if self._camera.config.mode == "orbit" else 0.0))

    def _show(self, view: CameraView) -> CameraView:
        # PyBullet applies a camera reset on its next frame, so it is not read back here.
        if _flat(view) != self._shown:
            distance, yaw, pitch, target = view
            p.resetDebugVisualizerCamera(
                distance, yaw, pitch, target, physicsClientId=self._sim.client
            )
            self._shown = _flat(view)
        return view


def _flat(view: CameraView) -> tuple[float, ...]:
    return (view[0], view[1], view[2], *view[3])


def configure_visualizer(
    client: int,
    enable_structure_transparency: bool,
    enable_shadows: bool,
    enable_collision_shapes: bool,
) -> None:
    """Apply visualizer flags to a GUI client."""
    p.configureDebugVisualizer(p.COV_ENABLE_SHADOWS, int(enable_shadows), physicsClientId=client)
    p.configureDebugVisualizer(
        p.COV_ENABLE_WIREFRAME, int(enable_collision_shapes), physicsClientId=client
    )
    if enable_structure_transparency:
        p.configureDebugVisualizer(p.COV_ENABLE_RGB_BUFFER_PREVIEW, 0, physicsClientId=client)


def handle_keyboard(sim: SimulationKernel) -> None:
    """Poll GUI keys: SPACE toggles pause."""
    events = p.getKeyboardEvents(physicsClientId=sim.client)
    if events.get(ord(" "), 0) & p.KEY_WAS_TRIGGERED:
        if sim.is_paused:
            sim.resume()
        else:
            sim.pause()


class GuiApi:
    """Camera and visualizer methods of the simulation (mixed into MultiRobotSimulationCore).

    The view is computed headless too (recorders frame the scene with it); PyBullet is told
    only when a GUI is open.
    """

    # Provided by the simulation kernel.
    params: SimulationParams
    client: int
    is_gui: bool
    state: KinematicState
    _gui_camera: GuiCamera | None = None

    def setup_pybullet(self) -> None:
        """Hide the GUI side panels (no-op headless)."""
        if self.is_gui:
            p.configureDebugVisualizer(
                p.COV_ENABLE_GUI, int(self.params.enable_gui_panel), physicsClientId=self.client
            )

    def configure_visualizer(
        self, enable_structure_transparency: bool | None = None, enable_shadows: bool | None = None
    ) -> None:
        """Apply visualizer flags (defaults from params; no-op headless)."""
        if not self.is_gui:
            return
        prm = self.params
        configure_visualizer(
            self.client,
            prm.enable_structure_transparency
            if enable_structure_transparency is None
            else enable_structure_transparency,
            prm.enable_shadows if enable_shadows is None else enable_shadows,
            prm.enable_collision_shapes,
        )

    def compute_scene_bounds(self) -> tuple[list[float], list[float]]:
        """(center, extent) of all object positions; zeros when empty."""
        store = self.state
        return scene_bounds(store.position[store.live_rows()])

    def setup_camera(
        self,
        camera_config: dict[str, Any] | None = None,
        entity_positions: Sequence[Sequence[float]] | None = None,
    ) -> CameraView:
        """Frame the camera on the scene (per ``camera_config``) or on ``entity_positions``.

        Args:
            camera_config: A ``camera_config`` mapping (default: ``params.camera_config``).
            entity_positions: Frame these points instead of the scene.

        Returns:
            (distance, yaw, pitch, target) of the view.

        Raises:
            ValueError: for a bad ``camera_config``, or ``follow:NAME`` with no such body.

        The view is computed headless too (recorders use it); it is applied only with a GUI.
        """
        config = (
            self.params.camera
            if camera_config is None
            else parse_camera_config(camera_config, "setup_camera camera_config")
        )
        fov, aspect = gui_projection(self.client) if self.is_gui else (DEFAULT_FOV_DEG, 4 / 3)
        if entity_positions is not None and config.mode != "manual":
            points = np.asarray(entity_positions, dtype=float).reshape(-1, 3)
            view = box_view(points.min(axis=0), points.max(axis=0), config, fov, aspect)
        else:
            sim = cast("SimulationKernel", self)
            view = SceneCamera(sim, config, fov_deg=fov, aspect=aspect).view()
        if self.is_gui:
            distance, yaw, pitch, target = view
            p.resetDebugVisualizerCamera(distance, yaw, pitch, target, physicsClientId=self.client)
        return view

    def _start_gui_camera(self) -> None:
        """With a GUI: frame the window on the scene at the first step and keep it framed."""
        if self.is_gui and self._gui_camera is None:
            sim = cast("SimulationKernel", self)
            self._gui_camera = GuiCamera(sim)
            # A high number runs late: the camera frames what the other handlers did.
            sim.events.on(SimEvents.POST_STEP, self._gui_camera.on_post_step, priority=300)

    def _frame_gui_camera(self, *, restart: bool = False) -> None:
        """Frame the GUI window now (a run starts) or at the next step (``restart``)."""
        if self._gui_camera is not None:
            if restart:
                self._gui_camera.restart()
            else:
                self._gui_camera.frame()
