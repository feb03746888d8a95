"""Kinematic-limit helpers: scalar (Euclidean) or per-axis (box) limits on vectors.

A limit is one number (a bound on the vector's norm) or one number per axis (a bound on each
component). The reference API's ``geometry`` module (``fleet_async.geometry``) re-exports these
with ``Pose`` (``pose.py``), ``Path`` (``waypoints.py``) and the quaternion helpers
(``quaternions.py``). Positions are in metres, angles in radians.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence

import numpy as np

__all__ = ["ScalarOrAxes", "as_axes", "clamp_vec_to_limit", "is_scalar", "projected_axis_limit"]

ScalarOrAxes = float | Sequence[float] | np.ndarray
"""Scalar limit (a Euclidean-norm bound) or per-axis sequence (a box bound)."""


def is_scalar(v: object) -> bool:
    """Return True if ``v`` is a scalar (broadcastable) value rather than a per-axis one.

    Args:
        v: A limit or similar value.

    Returns:
        True for Python and numpy real numbers and 0-d arrays; False for anything else
        (lists, tuples, 1-d arrays, ...), which is treated as per-axis.
    """
    if isinstance(v, np.ndarray):
        return v.ndim == 0
    return isinstance(v, (numbers.Real, np.generic))


def as_axes(v: ScalarOrAxes, dim: int = 3) -> np.ndarray:
    """Coerce ``v`` to a new ``(dim,)`` float array, broadcasting a scalar to every axis.

    Args:
        v: A scalar, or ``dim`` per-axis values.
        dim: Number of axes.

    Returns:
        A float64 array of shape ``(dim,)`` that does not alias ``v``.

    Raises:
        ValueError: If ``v`` is array-like but its shape is not ``(dim,)``.
    """
    if is_scalar(v):
        return np.full(dim, float(v))  # type: ignore[arg-type]  # is_scalar checked it
    arr = np.array(v, dtype=np.float64)
    if arr.shape != (dim,):
        raise ValueError(f"expected a scalar or {dim} per-axis values, got {v!r}")
    return arr


def projected_axis_limit(
    limit: ScalarOrAxes, direction_unit: Sequence[float] | np.ndarray
) -> float:
    """Largest speed (or acceleration) ``v`` along ``direction_unit`` within the caps.

    For per-axis caps ``arr`` this is ``1 / max_i(|d[i]| / arr[i])``, the largest ``v`` with
    ``|d[i]| * v <= arr[i]`` for every axis; axes the direction does not move along impose no
    bound. A scalar cap is a Euclidean bound (as in ``clamp_vec_to_limit``), so it is returned
    unchanged.

    Args:
        limit: Scalar cap, or per-axis caps ``>= 0`` (``math.inf`` means unbounded).
        direction_unit: Unit travel direction with one component per axis.

    Returns:
        The bound along the direction; ``math.inf`` if no axis constrains it.

    Raises:
        ValueError: If the direction's length does not match the per-axis caps.
    """
    if is_scalar(limit):
        return float(limit)  # type: ignore[arg-type]  # is_scalar checked it
    caps = as_axes(limit, len(limit)).tolist()  # type: ignore[arg-type]  # not a scalar here
    direction = np.asarray(direction_unit, dtype=np.float64)
    if direction.shape != (len(caps),):
        raise ValueError(f"direction_unit: expected {len(caps)} components, got {direction_unit!r}")
    worst = 0.0
    for cap, d in zip(caps, direction.tolist(), strict=True):
        if d == 0.0:
            continue
        if cap == 0.0:
            return 0.0
        worst = max(worst, abs(d) / cap)
    return math.inf if worst == 0.0 else 1.0 / worst


def clamp_vec_to_limit(vec: Sequence[float] | np.ndarray, limit: ScalarOrAxes) -> np.ndarray:
    """Clamp a vector against a scalar or per-axis cap.

    A scalar cap is a Euclidean magnitude clamp (projection onto a sphere: direction kept,
    length at most ``limit``); a non-finite scalar returns ``vec`` unchanged. Per-axis caps
    clip each component to ``[-limit[i], limit[i]]`` (projection onto a box).

    Args:
        vec: The vector to clamp.
        limit: Scalar cap ``>= 0`` or one cap per component.

    Returns:
        The clamped vector (``vec`` itself, as an array, when nothing changes for a scalar cap).

    Raises:
        ValueError: If a scalar cap is negative, or per-axis caps do not match ``vec``.
    """
    v = np.asarray(vec, dtype=np.float64)
    if not is_scalar(limit):
        caps = as_axes(limit, v.shape[0])
        return np.clip(v, -caps, caps)
    cap = float(limit)  # type: ignore[arg-type]  # is_scalar checked it
    if not math.isfinite(cap):
        return v
    if cap < 0.0:
        raise ValueError(f"limit: expected a non-negative scalar cap, got {limit!r}")
    norm = math.sqrt(float(v @ v))
    return v * (cap / norm) if norm > cap else v
