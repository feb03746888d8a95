"""Camera views framed on the scene, shared by the GIF / MP4 recorder and the GUI.

A :class:`SceneCamera` turns a checked ``camera_config`` (``base/camera_config.py``) into a
``(distance, yaw, pitch, target)`` view for each frame:

- ``auto`` / ``top_down`` / ``orbit`` frame every body's extent seen so far in the run: the
  union of the AABBs (and positions) of every body at every frame the camera was asked for.
  The view starts on the whole scene, widens as soon as a body moves out of it and never
  narrows, so every robot stays in view and the camera does not pump.
- ``fleet`` frames the agents' extent now; it widens at once and narrows slowly.
- ``follow`` keeps the named body at the centre, at a distance fixed when it starts.
- ``manual`` is the configured view.

The distance is fitted, not guessed: the eight corners of the box to show are projected with
the camera's own view matrix, and the camera backs off until every corner is inside the field
of view, whatever the image's aspect ratio (``fit_distance``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import pybullet as p

from fleet_async.core.base.camera_config import CameraConfig

if TYPE_CHECKING:
    from fleet_async.core.base.params import SimulationParams
    from fleet_async.core.world.state import KinematicState

__all__ = [
    "CAMERA_PARAM_KEYS",
    "DEFAULT_FOV_DEG",
    "CameraSim",
    "CameraView",
    "SceneCamera",
    "box_view",
    "fit_distance",
    "parse_camera_params",
]

CameraView = tuple[float, float, float, list[float]]
"""(distance m, yaw deg, pitch deg, target [x, y, z] m) of a camera orbiting its target."""

DEFAULT_FOV_DEG = 60.0
"""Vertical field of view of recordings (degrees)."""
MANUAL_VIEW: CameraView = (10.0, 0.0, -45.0, [0.0, 0.0, 0.0])
"""``camera_mode: manual`` values for keys left out (the reference API's)."""
_PAD_FRACTION = 0.05  # room around the framed box, as a share of its width ...
_PAD_MIN = 0.25  # ... and at least this (m)
_FOLLOW_SPAN = 4.0  # metres of floor around a followed body
_MIN_SPAN = 3.0  # metres of floor a framed view shows at least (one robot is not a close-up)
_FLEET_SHRINK = 0.97  # per frame: how fast a fleet view narrows
_LEAD = (0.05, 0.3, 2.0)  # a side of the run's box that a body crosses moves past it by this
# share of the box's width, at least / at most so many metres


CAMERA_PARAM_KEYS = ("distance", "yaw", "pitch", "target")
"""Keys of a recording's ``camera_params`` (``camera_mode="manual"``)."""


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def parse_camera_params(params: Any) -> dict[str, Any]:
    """Check a recording's ``camera_params`` (its manual camera); return a copy.

    Raises:
        ValueError: naming the key and the bad value.
    """
    if not isinstance(params, dict):
        raise ValueError(
            f"recording camera_params: expected a dict with keys {list(CAMERA_PARAM_KEYS)}, "
            f"got {params!r}"
        )
    unknown = sorted(set(params) - set(CAMERA_PARAM_KEYS))
    if unknown:
        raise ValueError(
            f"recording camera_params: unknown key(s) {unknown}; "
            f"valid keys are {list(CAMERA_PARAM_KEYS)}"
        )
    for key in ("distance", "yaw", "pitch"):
        if key in params and not _is_number(params[key]):
            raise ValueError(
                f"recording camera_params.{key}: expected a number, got {params[key]!r}"
            )
    distance = params.get("distance", 1.0)
    if distance <= 0:
        raise ValueError(
            f"recording camera_params.distance: expected a number > 0 (m), got {distance!r}"
        )
    if "target" in params:
        target = params["target"]
        if not (
            isinstance(target, (list, tuple)) and len(target) == 3 and all(map(_is_number, target))
        ):
            raise ValueError(
                f"recording camera_params.target: expected [x, y, z] (m), got {target!r}"
            )
    return dict(params)


class CameraSim(Protocol):
    """What a camera needs from the simulation."""

    @property
    def params(self) -> SimulationParams: ...
    @property
    def state(self) -> KinematicState: ...
    @property
    def sim_objects(self) -> list[Any]: ...
    @property
    def agents(self) -> list[Any]: ...
    def get_aabb_bounds(
        self, object_ids: Sequence[int] | None = None
    ) -> tuple[list[float], list[float]] | None: ...
    def get_poses(self, object_ids: Sequence[int]) -> tuple[np.ndarray, np.ndarray]: ...


def fit_distance(
    lo: Sequence[float] | np.ndarray,
    hi: Sequence[float] | np.ndarray,
    yaw: float,
    pitch: float,
    fov_deg: float = DEFAULT_FOV_DEG,
    aspect: float = 4.0 / 3.0,
) -> float:
    """Distance (m) at which a camera aimed at the box's centre sees all of the box.

    Args:
        lo: Minimum corner of the box (m).
        hi: Maximum corner of the box (m).
        yaw: Camera yaw (degrees), PyBullet's ``computeViewMatrixFromYawPitchRoll`` convention.
        pitch: Camera pitch (degrees).
        fov_deg: Vertical field of view (degrees).
        aspect: Image width / height.
    """
    lo_a, hi_a = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    target = (lo_a + hi_a) / 2.0
    view = np.asarray(
        p.computeViewMatrixFromYawPitchRoll(target.tolist(), 1.0, yaw, pitch, 0.0, 2)
    ).reshape(4, 4)  # column-major: row-vector convention, points times this
    corners = np.array(
        [
            [x, y, z, 1.0]
            for x in (lo_a[0], hi_a[0])
            for y in (lo_a[1], hi_a[1])
            for z in (lo_a[2], hi_a[2])
        ]
    )
    cam = corners @ view  # camera frame at distance 1: looking down -z
    # Backing the camera off to distance d shifts every z by -(d - 1); a corner is in view
    # when |x| <= depth * tan(h/2) and |y| <= depth * tan(v/2), depth = -z.
    rel = cam[:, 2] + 1.0
    tan_v = math.tan(math.radians(fov_deg) / 2.0)
    tan_h = tan_v * aspect
    need = np.maximum(rel + np.abs(cam[:, 0]) / tan_h, rel + np.abs(cam[:, 1]) / tan_v)
    return max(float(need.max()), 1.0)


def _padded(lo: np.ndarray, hi: np.ndarray, min_span: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The box grown by the framing margin, and to at least ``min_span`` across in x and y."""
    span = float(max(hi[0] - lo[0], hi[1] - lo[1]))
    pad = max(_PAD_FRACTION * span, _PAD_MIN)
    lo, hi = lo - pad, hi + pad
    grow = np.maximum(min_span - (hi - lo), 0.0) / 2.0
    grow[2] = 0.0
    return lo - grow, hi + grow


def box_view(
    lo: Sequence[float] | np.ndarray,
    hi: Sequence[float] | np.ndarray,
    config: CameraConfig,
    fov_deg: float = DEFAULT_FOV_DEG,
    aspect: float = 4.0 / 3.0,
) -> CameraView:
    """The view of ``config``'s angles that frames the box ``lo`` .. ``hi`` (plus a margin)."""
    lo_p, hi_p = _padded(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float), _MIN_SPAN)
    yaw = 0.0 if config.yaw is None else config.yaw
    pitch = config.view_pitch
    distance = fit_distance(lo_p, hi_p, yaw, pitch, fov_deg, aspect) * config.auto_scale
    return distance, yaw, pitch, ((lo_p + hi_p) / 2.0).tolist()


class SceneCamera:
    """The views of one camera (a recording's, the GUI's) over a run.

    Args:
        sim: The simulation.
        config: The checked camera config (``sim.params.camera``, maybe ``with_mode(...)``).
        fov_deg: Vertical field of view of the image (degrees).
        aspect: Image width / height.
        where: What configured the camera, for error messages (``camera_config``, ``--camera``).

    Raises:
        ValueError: for ``follow:NAME`` when no body is called NAME.
    """

    def __init__(
        self,
        sim: CameraSim,
        config: CameraConfig,
        *,
        fov_deg: float = DEFAULT_FOV_DEG,
        aspect: float = 4.0 / 3.0,
        where: str = "camera_config",
    ) -> None:
        self._sim = sim
        self.config = config
        self.fov_deg = float(fov_deg)
        self.aspect = float(aspect)
        self._lo: np.ndarray | None = None  # the box seen so far (auto modes)
        self._hi: np.ndarray | None = None
        self._distance: float | None = None  # fleet: last distance; follow: the fixed one
        self._target = [0.0, 0.0, 0.0]  # follow: where the body was last seen
        self._followed = self._find(config.follow, where) if config.mode == "follow" else None

    def _find(self, name: str | None, where: str) -> Any:
        for obj in self._sim.sim_objects:
            if obj.name == name:
                return obj
        names = [obj.name for obj in self._sim.sim_objects[:12]]
        more = ", ..." if len(self._sim.sim_objects) > 12 else ""
        raise ValueError(
            f"{where}: follow:{name}: no body called {name!r} in the simulation "
            f"(bodies: {', '.join(map(str, names))}{more})"
        )

    def view(self, turn: float = 0.0) -> CameraView:
        """The view now; ``turn`` (degrees) is added to the yaw of an ``orbit`` camera."""
        mode = self.config.mode
        if mode == "manual":
            return self._manual()
        if mode == "follow":
            return self._follow()
        if mode == "fleet":
            return self._fleet()
        distance, yaw, pitch, target = self._whole_run()
        return distance, yaw + (turn if mode == "orbit" else 0.0), pitch, target

    def _scene_box(self, object_ids: Sequence[int] | None) -> tuple[np.ndarray, np.ndarray]:
        """The box holding the given bodies' AABBs and positions (default: every body)."""
        store = self._sim.state
        if object_ids is None:
            positions = store.position[store.live_rows()]
        else:
            positions = self._sim.get_poses(object_ids)[0]
        if len(positions):
            lo, hi = positions.min(axis=0), positions.max(axis=0)
        else:
            lo, hi = np.zeros(3), np.zeros(3)
        aabb = self._sim.get_aabb_bounds(object_ids)
        if aabb is not None:
            lo, hi = np.minimum(lo, aabb[0]), np.maximum(hi, aabb[1])
        return lo, hi

    def _whole_run(self) -> CameraView:
        lo, hi = self._scene_box(None)
        if self._lo is not None and self._hi is not None:
            # A side that a body crossed moves past it by a lead, so the body is not pinned to
            # the edge of the picture and the view widens in a few steps rather than every frame.
            share, least, most = _LEAD
            width = float(max(self._hi[:2] - self._lo[:2]))
            lead = np.array([min(max(share * width, least), most)] * 2 + [0.0])
            lo = np.where(lo < self._lo, lo - lead, self._lo)
            hi = np.where(hi > self._hi, hi + lead, self._hi)
        self._lo, self._hi = lo, hi
        return box_view(lo, hi, self.config, self.fov_deg, self.aspect)

    def _fleet(self) -> CameraView:
        agents = self._sim.agents
        lo, hi = self._scene_box([a.object_id for a in agents] if agents else None)
        distance, yaw, pitch, target = box_view(lo, hi, self.config, self.fov_deg, self.aspect)
        if self._distance is not None:
            distance = max(distance, self._distance * _FLEET_SHRINK)
        self._distance = distance
        return distance, yaw, pitch, target

    def _follow(self) -> CameraView:
        obj = self._followed
        if obj is not None and obj.sim_core is not None:  # a removed body keeps the last view
            self._target = [float(v) for v in obj.get_pose().position]
            if self._distance is None:
                lo, hi = self._scene_box([obj.object_id])
                lo, hi = _padded(lo, hi, _FOLLOW_SPAN)
                yaw = 0.0 if self.config.yaw is None else self.config.yaw
                fitted = fit_distance(
                    lo, hi, yaw, self.config.view_pitch, self.fov_deg, self.aspect
                )
                configured = self.config.distance
                self._distance = (
                    configured if configured is not None else fitted * self.config.auto_scale
                )
        yaw = 0.0 if self.config.yaw is None else self.config.yaw
        return float(self._distance or 1.0), yaw, self.config.view_pitch, list(self._target)

    def _manual(self) -> CameraView:
        cfg = self.config
        distance, yaw, pitch, target = MANUAL_VIEW
        return (
            distance if cfg.distance is None else cfg.distance,
            yaw if cfg.yaw is None else cfg.yaw,
            pitch if cfg.pitch is None else cfg.pitch,
            list(target) if cfg.target is None else list(cfg.target),
        )
