"""Vectors as parameters and between frames.

Scalar-or-per-axis parameters (``normalize_vector_param``), strict positions and quaternions
(``strict_vector``, ``as_position``, ``as_orientation``) and body-to-world velocities. Frames and
units: positions are metres in the world frame unless stated, angles are radians, quaternions
are ``(x, y, z, w)`` like PyBullet.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np

from fleet_async.core.geometry.quaternions import rotate_vector

__all__ = [
    "Vector",
    "as_orientation",
    "as_position",
    "body_to_world_velocity_2d",
    "body_to_world_velocity_3d",
    "normalize_vector_param",
    "strict_vector",
]

Vector = Sequence[float] | np.ndarray


def body_to_world_velocity_2d(vx_body: float, vy_body: float, yaw: float) -> tuple[float, float]:
    """Rotate a planar body-frame velocity into the world frame by ``yaw`` only.

    Args:
        vx_body: Forward velocity in the body frame (m/s).
        vy_body: Leftward velocity in the body frame (m/s).
        yaw: Heading of the body in the world frame (radians, counter-clockwise from +X).

    Returns:
        ``(vx, vy)`` in the world frame (m/s). For example ``(1, 0)`` at ``yaw = pi/2`` is
        ``(0, 1)``.
    """
    c, s = math.cos(yaw), math.sin(yaw)
    return (c * vx_body - s * vy_body, s * vx_body + c * vy_body)


def body_to_world_velocity_3d(
    vx_body: float, vy_body: float, vz_body: float, orientation: Vector
) -> tuple[float, float, float]:
    """Rotate a body-frame velocity into the world frame by a full orientation.

    Args:
        vx_body: Velocity along the body X axis (m/s).
        vy_body: Velocity along the body Y axis (m/s).
        vz_body: Velocity along the body Z axis (m/s).
        orientation: Body orientation in the world frame, quaternion ``(x, y, z, w)``;
            normalised here.

    Returns:
        ``(vx, vy, vz)`` in the world frame (m/s).

    Raises:
        ValueError: If ``orientation`` is not 4 numbers or has zero norm.
    """
    vx, vy, vz = rotate_vector((vx_body, vy_body, vz_body), orientation)
    return (float(vx), float(vy), float(vz))


def normalize_vector_param(value: float | Vector, param_name: str, dim: int = 3) -> np.ndarray:
    """Turn a scalar or per-axis parameter (e.g. a velocity limit) into a ``(dim,)`` array.

    Args:
        value: One number for every axis, or ``dim`` numbers.
        param_name: Name used in error messages.
        dim: Number of axes.

    Returns:
        A new float64 array of shape ``(dim,)``: ``normalize_vector_param(2.0, "v", 3)`` is
        ``[2, 2, 2]``.

    Raises:
        ValueError: Naming ``param_name``, if ``value`` is not numeric, has the wrong length or
            contains NaN or infinity.
    """
    # The message is built only on failure: formatting an array costs more than the checks.
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nesting
        raise ValueError(_expected(param_name, dim, value)) from exc
    if raw.dtype.kind not in "iuf":  # rejects bools, strings and arbitrary objects
        raise ValueError(_expected(param_name, dim, value))
    arr = np.full(dim, float(raw)) if raw.ndim == 0 else raw.astype(np.float64)
    if arr.shape != (dim,):
        raise ValueError(_expected(param_name, dim, value))
    if not np.isfinite(arr).all():
        raise ValueError(f"{param_name}: expected finite numbers, got {value!r}")
    return arr


def _expected(param_name: str, dim: int, value: Any) -> str:
    return f"{param_name}: expected a number or {dim} numbers, got {value!r}"


def strict_vector(value: Any, name: str, dim: int) -> np.ndarray:
    """Like normalize_vector_param, but a scalar is an error: positions are never broadcast."""
    if isinstance(value, (numbers.Number, np.generic, str)) or getattr(value, "ndim", 1) == 0:
        raise ValueError(f"{name}: expected {dim} numbers, got {value!r}")
    return normalize_vector_param(value, name, dim)


def as_position(value: Any, field: str = "position") -> np.ndarray:
    """Validate ``[x, y, z]`` into a float array, or raise ValueError naming ``field``."""
    arr = (
        np.asarray(value, dtype=float) if not isinstance(value, np.ndarray) else value.astype(float)
    )
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise ValueError(f"{field}: expected 3 finite numbers [x, y, z], got {value!r}")
    return arr


def as_orientation(value: Any, field: str = "orientation") -> np.ndarray:
    """Validate a quaternion (x, y, z, w) into a unit float array, or raise ValueError."""
    arr = (
        np.asarray(value, dtype=float) if not isinstance(value, np.ndarray) else value.astype(float)
    )
    if arr.shape != (4,) or not np.isfinite(arr).all():
        raise ValueError(f"{field}: expected 4 finite numbers [x, y, z, w], got {value!r}")
    norm = math.sqrt(float(arr @ arr))
    if norm < 1e-12:
        raise ValueError(f"{field}: zero quaternion {value!r} is not a rotation")
    return arr if abs(norm - 1.0) < 1e-12 else arr / norm
