"""``SimulationParams.camera_config``: what the GUI camera and the recorder look at.

The mapping keeps the reference API's keys (``camera_mode``, ``camera_view_type``,
``camera_auto_scale``, ``camera_distance``, ``camera_yaw``, ``camera_pitch``,
``camera_target``) and widens ``camera_mode``:

- ``auto`` (default): the whole scene, every body's extent seen so far in the run; the view
  widens when a body moves out of it and never narrows, so every robot stays in view.
- ``top_down``: ``auto`` looking straight down (as ``camera_view_type: top_down``).
- ``orbit``: ``auto`` with the yaw turning.
- ``fleet``: follows the fleet: the agents' extent now (widening at once, narrowing slowly).
- ``follow:NAME``: follows the body called NAME (its name in the scenario), at a fixed distance.
- ``manual``: ``camera_distance``, ``camera_yaw``, ``camera_pitch``, ``camera_target``.

In every mode but ``manual``, ``camera_yaw`` / ``camera_pitch`` set the viewing angles
(degrees; defaults 0 and -60, or -89.9 top-down) and ``camera_auto_scale`` widens (> 1) or
tightens (< 1) the framing. The command line's ``--camera MODE`` sets ``camera_mode``. This
module only checks and parses the mapping; ``view/camera.py`` computes the views.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = [
    "CAMERA_KEYS",
    "CAMERA_MODES",
    "DEFAULT_PITCH",
    "TOP_DOWN_PITCH",
    "CameraConfig",
    "parse_camera_config",
    "parse_camera_mode",
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
"""The keys a ``camera_config`` mapping may hold."""

CAMERA_MODES = ("auto", "top_down", "orbit", "fleet", "follow:NAME", "manual")
"""The values of ``camera_mode`` (and of the command line's ``--camera``)."""

DEFAULT_PITCH = -60.0
"""Degrees below the horizon of the framed views: steep enough that racks two metres tall do
not hide the robots in the aisle behind them, flat enough to show heights."""
TOP_DOWN_PITCH = -89.9
"""Straight down (PyBullet's yaw / pitch camera is undefined at exactly -90)."""


@dataclass(frozen=True)
class CameraConfig:
    """A checked ``camera_config``.

    Attributes:
        mode: ``auto``, ``orbit``, ``fleet``, ``follow`` or ``manual`` (``top_down`` is
            ``auto`` with ``top_down`` set).
        follow: The followed body's name (mode ``follow``).
        top_down: Look straight down.
        auto_scale: Framing factor (> 1 leaves more room around the scene).
        distance: ``camera_distance`` (m), if given.
        yaw: ``camera_yaw`` (degrees), if given.
        pitch: ``camera_pitch`` (degrees), if given.
        target: ``camera_target`` ([x, y, z] m), if given.
    """

    mode: str = "auto"
    follow: str | None = None
    top_down: bool = False
    auto_scale: float = 1.0
    distance: float | None = None
    yaw: float | None = None
    pitch: float | None = None
    target: tuple[float, float, float] | None = None

    @property
    def label(self) -> str:
        """The mode as written: ``top_down``, ``follow:NAME``, ..."""
        if self.mode == "follow":
            return f"follow:{self.follow}"
        return "top_down" if self.mode == "auto" and self.top_down else self.mode

    @property
    def view_pitch(self) -> float:
        """The pitch (degrees) of the framed views."""
        if self.pitch is not None:
            return self.pitch
        return TOP_DOWN_PITCH if self.top_down else DEFAULT_PITCH

    def with_mode(self, text: Any, where: str) -> CameraConfig:
        """This config with ``camera_mode`` replaced by ``text`` (``--camera``, a recorder).

        Raises:
            ValueError: for a bad mode, naming ``where`` and the value.
        """
        mode, follow = parse_camera_mode(text, where)
        return CameraConfig(
            mode="auto" if mode == "top_down" else mode,
            follow=follow,
            top_down=mode == "top_down" or (self.top_down and mode != "manual"),
            auto_scale=self.auto_scale,
            distance=self.distance,
            yaw=self.yaw,
            pitch=self.pitch,
            target=self.target,
        )


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def parse_camera_mode(text: Any, where: str = "camera_mode") -> tuple[str, str | None]:
    """``(mode, followed name or None)`` of a ``camera_mode`` / ``--camera`` value.

    Raises:
        ValueError: naming ``where``, the value and the valid modes.
    """
    if isinstance(text, str):
        mode, _, name = text.partition(":")
        mode = mode.strip().replace("-", "_")
        if mode == "follow" and name.strip():
            return "follow", name.strip()
        if mode in CAMERA_MODES and not name:
            return mode, None
    raise ValueError(
        f"{where}: expected one of {list(CAMERA_MODES)} (follow:NAME names a body), got {text!r}"
    )


def parse_camera_config(
    config: Mapping[str, Any] | None, where: str = "camera_config"
) -> CameraConfig:
    """Check a ``camera_config`` mapping and return it parsed.

    Raises:
        ValueError: for an unknown key or a bad value, naming ``where``, the key and the value.
    """
    cfg = dict(config or {})
    unknown = sorted(set(cfg) - set(CAMERA_KEYS))
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown}; valid keys are {list(CAMERA_KEYS)}")
    view = cfg.get("camera_view_type", "perspective")
    if view not in ("perspective", "top_down"):
        raise ValueError(
            f"{where}.camera_view_type: expected 'perspective' or 'top_down', got {view!r}"
        )
    for key in ("camera_auto_scale", "camera_distance", "camera_yaw", "camera_pitch"):
        if key in cfg and not _number(cfg[key]):
            raise ValueError(f"{where}.{key}: expected a number, got {cfg[key]!r}")
    for key in ("camera_auto_scale", "camera_distance"):
        if key in cfg and cfg[key] <= 0:
            raise ValueError(f"{where}.{key}: expected a number > 0, got {cfg[key]!r}")
    target = cfg.get("camera_target")
    if target is not None and not (
        isinstance(target, (list, tuple)) and len(target) == 3 and all(map(_number, target))
    ):
        raise ValueError(f"{where}.camera_target: expected [x, y, z] (m), got {target!r}")
    base = CameraConfig(
        top_down=view == "top_down",
        auto_scale=float(cfg.get("camera_auto_scale", 1.0)),
        distance=None if "camera_distance" not in cfg else float(cfg["camera_distance"]),
        yaw=None if "camera_yaw" not in cfg else float(cfg["camera_yaw"]),
        pitch=None if "camera_pitch" not in cfg else float(cfg["camera_pitch"]),
        target=None if target is None else (float(target[0]), float(target[1]), float(target[2])),
    )
    return base.with_mode(cfg.get("camera_mode", "auto"), f"{where}.camera_mode")
