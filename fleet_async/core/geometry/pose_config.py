"""Reading poses out of configuration values."""

from __future__ import annotations

import math
from typing import Any

from fleet_async.core.geometry.pose import Pose

__all__ = ["pose_from_config"]


def pose_from_config(value: Any, yaw: Any = None, *, field_name: str = "pose") -> Pose:
    """Turn a config value into a Pose.

    Accepts a Pose, ``[x, y, z]`` (with optional ``yaw`` in radians), or a mapping with
    ``position`` plus one of ``orientation`` (quaternion x, y, z, w), ``yaw`` or
    ``rpy`` ([roll, pitch, yaw] in radians).

    Raises:
        ValueError: naming ``field_name`` and the bad value.
    """
    try:
        return _pose_from_config(value, yaw, field_name)
    except ValueError as exc:
        message = str(exc)
        if message.startswith(field_name):
            raise
        raise ValueError(f"{field_name}: {message}") from None


def _pose_from_config(value: Any, yaw: Any, field_name: str) -> Pose:
    if isinstance(value, Pose):
        if yaw is not None:
            raise ValueError(f"{field_name}: 'yaw' cannot be combined with a Pose object")
        return value
    if isinstance(value, dict):
        unknown = set(value) - {"position", "orientation", "yaw", "rpy"}
        if unknown:
            raise ValueError(
                f"{field_name}: unknown key(s) {sorted(unknown)}; "
                "expected position, orientation, yaw or rpy"
            )
        position = value.get("position", [0.0, 0.0, 0.0])
        given = [k for k in ("orientation", "yaw", "rpy") if k in value]
        if len(given) + (yaw is not None) > 1:
            raise ValueError(
                f"{field_name}: give one of 'orientation', 'yaw' or 'rpy', not {given}"
            )
        if "orientation" in value:
            return Pose(position, value["orientation"])
        if "rpy" in value:
            return Pose.from_euler(
                *_three(position, f"{field_name}.position"),
                *_three(value["rpy"], f"{field_name}.rpy"),
            )
        return _pose_from_config(position, value.get("yaw", yaw), field_name)
    if isinstance(value, (list, tuple)):
        if yaw is None:
            return Pose(list(value))
        if isinstance(yaw, bool) or not isinstance(yaw, (int, float)) or not math.isfinite(yaw):
            raise ValueError(f"{field_name}.yaw: expected a finite number (radians), got {yaw!r}")
        if len(value) != 3:
            raise ValueError(f"{field_name}: expected [x, y, z], got {value!r}")
        x, y, z = value
        return Pose.from_euler(x, y, z, yaw=float(yaw))
    raise ValueError(f"{field_name}: expected a Pose, [x, y, z] or a mapping, got {value!r}")


def _three(numbers: Any, what: str) -> list[float]:
    ok = isinstance(numbers, (list, tuple)) and len(numbers) == 3
    if not ok or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
        for v in numbers
    ):
        raise ValueError(f"{what}: expected 3 finite numbers, got {numbers!r}")
    return [float(v) for v in numbers]
