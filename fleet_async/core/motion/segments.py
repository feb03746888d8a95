"""Segment math of the kinematic engine: limits, headings, per-axis caps, the trapezoid.

A segment moves a body from a start pose to a target pose; its progress ``u`` in [0, 1] follows
a trapezoidal velocity profile (:func:`trapezoid_duration`, :func:`trapezoid_progress`) whose
limits come from :class:`MotionLimits` through :func:`axis_cap` (see ``kinematics.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fleet_async.core.base.types import MovementDirection
from fleet_async.core.geometry.quaternions import quat_from_euler, yaw_from_quats

__all__ = [
    "EPS_ANGLE",
    "EPS_LEN",
    "PROFILE_TERMS",
    "MotionLimits",
    "as_floats",
    "axis_cap",
    "checked_limit",
    "heading_toward",
    "profile_terms",
    "segment_rates",
    "trapezoid_duration",
    "trapezoid_progress",
]

EPS_LEN = 1e-9  # m: shorter segments are skipped
EPS_ANGLE = 1e-9  # rad: smaller rotations are skipped


@dataclass(frozen=True)
class MotionLimits:
    """Kinematic limits of one agent; each is a scalar (Euclidean) or per-axis (x, y, z)."""

    max_linear_vel: float | tuple[float, float, float]
    max_linear_accel: float | tuple[float, float, float]
    max_angular_vel: float | tuple[float, float, float]
    max_angular_accel: float | tuple[float, float, float]


def checked_limit(value: Any, field: str) -> float | tuple[float, float, float]:
    """A scalar or per-axis (x, y, z) limit, validated: every number finite (or ``inf``) and > 0.

    Raises:
        ValueError: naming ``field`` (e.g. ``"ControllerParams.max_linear_vel"``) and the value.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if not (math.isfinite(value) or value == math.inf) or value <= 0:
            raise ValueError(f"{field}: expected a number > 0, got {value!r}")
        return float(value)
    try:
        items = [float(v) for v in value]
    except (TypeError, ValueError):
        raise ValueError(f"{field}: expected a number or [x, y, z], got {value!r}") from None
    if len(items) != 3 or not all(v > 0 for v in items):
        raise ValueError(f"{field}: expected 3 numbers > 0 (x, y, z), got {value!r}")
    return (items[0], items[1], items[2])


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


def trapezoid_duration(rate: float, accel: float) -> tuple[float, float, float]:
    """Shape of the fastest rest-to-rest profile covering ``u`` from 0 to 1.

    Args:
        rate: Largest rate of ``u`` (1/s); may be ``inf``.
        accel: Largest acceleration of ``u`` (1/s^2); may be ``inf``.

    Returns:
        ``(peak, t_acc, t_end)``: the cruise rate (lower than ``rate`` when the segment is too
        short to reach it: a triangle), the seconds spent accelerating (and again braking),
        and the profile's duration. ``t_end`` is 0 when both limits are infinite.
    """
    peak = min(rate, math.sqrt(accel)) if math.isfinite(accel) else rate
    if not math.isfinite(peak):
        return math.inf, 0.0, 0.0
    t_acc = peak / accel if math.isfinite(accel) else 0.0
    return peak, t_acc, t_acc + 1.0 / peak


PROFILE_TERMS = ("pk", "pk_half", "pk_t_acc", "pk_divisor", "pk_t_acc_half", "pk_t_brake")
"""Names of :func:`profile_terms`' values, in order."""


def profile_terms(peak: float, t_acc: float, t_end: float) -> tuple[float, ...]:
    """The terms :func:`trapezoid_progress` takes for the profile ``(peak, t_acc, t_end)`` of
    :func:`trapezoid_duration`, worked out once per segment rather than once per step.

    Profiles with an infinite acceleration (``t_acc`` 0) or an infinite rate (``t_end`` 0)
    get terms that need no division by zero and give ``u = 1`` from ``t_end`` on.
    """
    if not math.isfinite(peak):  # ends at once: braking from t = 0, to u = 1
        return 0.0, 0.0, 0.0, 1.0, 0.0, 0.0
    if t_acc <= 0.0:  # no ramps: cruise until t_end, then u = 1
        return peak, 0.5 * peak, 0.0, 1.0, 0.0, t_end
    return peak, 0.5 * peak, t_acc, t_acc, 0.5 * t_acc, t_end - t_acc


def trapezoid_progress(
    t: np.ndarray,
    terms: tuple[np.ndarray, ...] | np.ndarray,
    t_end: np.ndarray,
) -> np.ndarray:
    """Progress ``u(t)`` of rest-to-rest profiles (see :func:`trapezoid_duration`), in [0, 1].

    Accelerates at ``peak / t_acc`` for ``t_acc`` seconds, cruises at ``peak`` and brakes
    symmetrically to stop at ``u = 1`` at ``t_end``; exact at every ``t``, so sampling it once
    per step never exceeds the limits, whatever the step.

    Args:
        t: Seconds since each profile started.
        terms: The :func:`profile_terms` of each profile: six arrays, or one ``(6, n)`` array.
        t_end: Each profile's duration.
    """
    peak, half_peak, t_acc, divisor, half_t_acc, t_brake = terms
    cruise = peak * (t - half_t_acc)
    rising = half_peak * t * t / divisor
    left = np.maximum(t_end - t, 0.0)
    braking = 1.0 - half_peak * left * left / divisor
    u = np.where(t < t_acc, rising, np.where(t > t_brake, braking, cruise))
    # Each branch is >= 0 where it is chosen (rising and cruise by construction, braking is
    # at least 1 - peak * t_acc / 2 >= 1/2), so only the top needs a clip.
    return np.minimum(u, 1.0, out=u)


def axis_cap(limit: np.ndarray, scalar: bool, direction: np.ndarray) -> float:
    """Largest magnitude along unit ``direction`` allowed by a scalar or per-axis limit."""
    if scalar:
        return float(limit[0])
    ratios = np.abs(direction) / limit
    worst = float(ratios.max())
    return math.inf if worst == 0.0 else 1.0 / worst


def segment_rates(
    limit: np.ndarray, accel: np.ndarray, scalar: bool, direction: tuple[float, ...], span: float
) -> tuple[float, float]:
    """Largest rate and acceleration of ``u`` (1/s, 1/s^2) for a segment that covers ``span``
    (m, or rad for a turn) along unit ``direction`` within a scalar or per-axis limit pair."""
    if scalar:
        return float(limit[0]) / span, float(accel[0]) / span
    unit = np.array(direction)
    return axis_cap(limit, False, unit) / span, axis_cap(accel, False, unit) / span


def as_floats(values: np.ndarray | list[float]) -> list[float]:
    """A pose part (position or quaternion) as Python floats, as float64 gives them."""
    if type(values) is list:
        return values
    return np.asarray(values, dtype=float).tolist()
