"""GUI concerns: visualizer flags, camera framing and keyboard shortcuts (no-ops headless).

``GuiApi`` is the simulation's side of it (``setup_camera``, ``configure_visualizer``, ...).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pybullet as p

if TYPE_CHECKING:
    from fleet_async.core.sim.params import SimulationParams
    from fleet_async.core.simulation import MultiRobotSimulationCore
    from fleet_async.core.world.state import KinematicState

__all__ = [
    "CAMERA_KEYS",
    "GuiApi",
    "camera_view",
    "configure_visualizer",
    "handle_keyboard",
    "scene_bounds",
]

CAMERA_KEYS = (
    "camera_mode",
    "camera_view_type",
    "camera_auto_scale",
    "camera_distance",
    "camera_yaw",
    "camera_pitch",
    "camera_target",
)


def scene_bounds(positions: np.ndarray) -> tuple[list[float], list[float]]:
    """(center, extent) of a set of positions: mean point and max - min per axis."""
    if len(positions) == 0:
        return [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    center = positions.mean(axis=0)
    extent = positions.max(axis=0) - positions.min(axis=0)
    return center.tolist(), extent.tolist()


def camera_view(
    camera_config: dict[str, Any] | None, center: Sequence[float], extent: Sequence[float]
) -> tuple[float, float, float, list[float]]:
    """Resolve (distance, yaw, pitch, target) from a camera config and the scene bounds.

    ``camera_mode`` "auto" (default) frames the scene; "manual" uses ``camera_distance``,
    ``camera_yaw``, ``camera_pitch`` (degrees) and ``camera_target``. ``camera_view_type``
    "top_down" looks straight down; "perspective" (default) from 45 degrees.

    Raises:
        ValueError: for an unknown key or mode, naming it.
    """
    cfg = dict(camera_config or {})
    unknown = sorted(set(cfg) - set(CAMERA_KEYS))
    if unknown:
        raise ValueError(
            f"camera_config: unknown key(s) {unknown}; valid keys are {list(CAMERA_KEYS)}"
        )
    mode = cfg.get("camera_mode", "auto")
    if mode == "manual":
        return (
            float(cfg.get("camera_distance", 10.0)),
            float(cfg.get("camera_yaw", 0.0)),
            float(cfg.get("camera_pitch", -45.0)),
            [float(v) for v in cfg.get("camera_target", [0.0, 0.0, 0.0])],
        )
    if mode != "auto":
        raise ValueError(f"camera_config.camera_mode: expected 'auto' or 'manual', got {mode!r}")
    view = cfg.get("camera_view_type", "perspective")
    if view not in ("perspective", "top_down"):
        raise ValueError(
            f"camera_config.camera_view_type: expected 'perspective' or 'top_down', got {view!r}"
        )
    scale = float(cfg.get("camera_auto_scale", 1.0))
    size = max(max(extent[0], extent[1]), 1.0)
    distance = size * scale / (2.0 * math.tan(math.radians(30.0))) + 1.0
    pitch = -89.9 if view == "top_down" else -45.0
    return distance, 0.0, pitch, list(center)


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


def handle_keyboard(sim: MultiRobotSimulationCore) -> None:
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
    ) -> tuple[float, float, float, list[float]]:
        """Frame the camera on the scene or ``entity_positions``.

        Returns:
            (distance, yaw, pitch, target) of the view.

        The view is computed headless too (recorders use it); it is applied only with a GUI.
        """
        if entity_positions is not None:
            center, extent = scene_bounds(np.asarray(entity_positions, dtype=float).reshape(-1, 3))
        else:
            center, extent = self.compute_scene_bounds()
        view = camera_view(
            camera_config if camera_config is not None else self.params.camera_config,
            center,
            extent,
        )
        if self.is_gui:
            distance, yaw, pitch, target = view
            p.resetDebugVisualizerCamera(distance, yaw, pitch, target, physicsClientId=self.client)
        return view
