"""Segment math of the kinematic engine: limits, headings, per-axis caps, the braking rate.

A segment moves a body from a start pose to a target pose; its progress ``u`` in [0, 1] follows
a trapezoidal rate profile whose limits come from :class:`MotionLimits` through
:func:`axis_cap`, and whose braking follows :func:`braking_rate` so that the last step lands
exactly on the target (see ``kinematics.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fleet_async.core.base.types import MovementDirection
from fleet_async.core.geometry.quaternions import quat_from_euler, yaw_from_quats

__all__ = ["EPS_ANGLE", "EPS_LEN", "MotionLimits", "axis_cap", "braking_rate", "heading_toward"]

EPS_LEN = 1e-9  # m: shorter segments are skipped
EPS_ANGLE = 1e-9  # rad: smaller rotations are skipped


@dataclass(frozen=True)
class MotionLimits:
    """Kinematic limits of one agent; each is a scalar (Euclidean) or per-axis (x, y, z)."""

    max_linear_vel: float | tuple[float, float, float]
    max_linear_accel: float | tuple[float, float, float]
    max_angular_vel: float | tuple[float, float, float]
    max_angular_accel: float | tuple[float, float, float]


def heading_toward(
    direction: MovementDirection, pos: np.ndarray, orn: np.ndarray, target: np.ndarray
) -> np.ndarray | None:
    """Orientation a differential robot turns to before driving to ``target`` (None: no turn)."""
    dx, dy = float(target[0] - pos[0]), float(target[1] - pos[1])
    if math.hypot(dx, dy) < EPS_LEN:
        return None
    yaw = math.atan2(dy, dx)
    if direction is MovementDirection.AUTO:
        current = float(yaw_from_quats(orn[None, :])[0])
        off = abs((yaw - current + math.pi) % (2 * math.pi) - math.pi)
        direction = MovementDirection.BACKWARD if off > math.pi / 2 else MovementDirection.FORWARD
    if direction is MovementDirection.BACKWARD:
        yaw += math.pi
    return quat_from_euler(0.0, 0.0, yaw)


def braking_rate(remaining: np.ndarray, accel: np.ndarray, dt: float) -> np.ndarray:
    """Fastest rate from which the discrete braking sequence still stops within ``remaining``.

    Braking as hard as allowed from rate ``v = (j + f) * c`` (``c = accel * dt``, j integer,
    f in (0, 1]) moves ``v, v - c, ..., f * c`` per step and covers
    ``dt * c * (j + 1) * (f + j / 2)``. Inverting that for the largest ``v`` that fits gives a
    profile that never brakes harder than ``accel``, ends with a last step of at most ``c``
    (so the final stop is within the limit too), and lands exactly on the target.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        c = accel * dt
        scaled = remaining / (dt * c)
        j = np.maximum(np.ceil((np.sqrt(1.0 + 8.0 * scaled) - 1.0) / 2.0) - 1.0, 0.0)
        f = np.clip(scaled / (j + 1.0) - j / 2.0, 0.0, 1.0)
        rate = (j + f) * c
    return np.where(np.isfinite(c), rate, np.inf)


def axis_cap(limit: np.ndarray, scalar: bool, direction: np.ndarray) -> float:
    """Largest magnitude along unit ``direction`` allowed by a scalar or per-axis limit."""
    if scalar:
        return float(limit[0])
    ratios = np.abs(direction) / limit
    worst = float(ratios.max())
    return math.inf if worst == 0.0 else 1.0 / worst
