"""Axis-aligned grids: world position to grid index and back, and visiting every grid point.

Grid index ``i`` on an axis sits at ``offset + i * spacing`` on that axis (metres, world frame).
The conversions are always 3-D, as in the reference API: 2-D input (``[x, y]``, ``[sx, sy]``)
is taken as lying in the plane of index 0 on Z.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from fleet_async.core.geometry.vectors import Vector, normalize_vector_param, strict_vector

__all__ = [
    "grid_execution",
    "grid_to_world",
    "grid_to_world_2d",
    "world_to_grid",
    "world_to_grid_2d",
]


def world_to_grid(pos: Vector, spacing: float | Vector, offset: Vector | None = None) -> list[int]:
    """Convert a world position to the nearest 3-D grid index.

    Args:
        pos: ``[x, y, z]`` in metres (or ``[x, y]``: z = 0).
        spacing: Grid spacing per axis (or one value for all), metres, each > 0; two values
            for X and Y leave Z at 1.
        offset: World position of grid index ``[0, 0, 0]`` (default: the origin).

    Returns:
        ``[ix, iy, iz]``, each ``round((pos - offset) / spacing)`` with halves rounded up.

    Raises:
        ValueError: If a vector has the wrong length, or a spacing is not > 0.
    """
    position = strict_vector(_as_3d(pos, 0.0), "pos", 3)
    step, origin = _grid_frame(spacing, offset)
    return [math.floor(v + 0.5) for v in ((position - origin) / step).tolist()]


def grid_to_world(
    grid: Sequence[int], spacing: float | Vector, offset: Vector | None = None
) -> list[float]:
    """Convert a 3-D grid index to its world position.

    Args:
        grid: ``[ix, iy, iz]`` (or ``[ix, iy]``: iz = 0).
        spacing: Grid spacing per axis (or one value for all), metres, each > 0; two values
            for X and Y leave Z at 1.
        offset: World position of grid index ``[0, 0, 0]`` (default: the origin).

    Returns:
        ``[x, y, z]`` in metres: ``offset + grid * spacing``.

    Raises:
        ValueError: If a vector has the wrong length, or a spacing is not > 0.
    """
    index = strict_vector(_as_3d(grid, 0), "grid", 3)
    step, origin = _grid_frame(spacing, offset)
    return (origin + index * step).tolist()


def world_to_grid_2d(pos: Vector, spacing: float | Vector) -> list[int]:
    """2-D wrapper for :func:`world_to_grid`: ``[x, y]`` and ``[sx, sy]`` to ``[ix, iy, 0]``.

    Three values, as the reference implementation returns (a script unpacks or indexes them).
    """
    xy = strict_vector(pos, "pos", 2)
    sxy = normalize_vector_param(spacing, "spacing", 2)
    return world_to_grid([xy[0], xy[1], 0.0], [sxy[0], sxy[1], 1.0])


def grid_to_world_2d(grid: Sequence[int], spacing: float | Vector) -> list[float]:
    """2-D wrapper for :func:`grid_to_world`: ``[ix, iy]`` and ``[sx, sy]`` to ``[x, y, 0.0]``.

    Three values, as the reference implementation returns.
    """
    ij = strict_vector(grid, "grid", 2)
    sxy = normalize_vector_param(spacing, "spacing", 2)
    return grid_to_world([ij[0], ij[1], 0], [sxy[0], sxy[1], 1.0])


def grid_execution(
    grid_num: Sequence[int] | None = None,
    spacing: float | Vector | None = None,
    offset: Vector | None = None,
    func: Callable[..., Any] | None = None,
    args: Mapping[str, Any] | None = None,
) -> None:
    """Call ``func(grid_index, world_pos, **args)`` at every point of a 3-D grid.

    Points are visited with Z varying fastest, then Y, then X (the reference implementation's
    order): for ``grid_num=[2, 2, 1]`` the order is ``[0,0,0], [0,1,0], [1,0,0], [1,1,0]``.
    With ``func=None`` nothing is called.

    Args:
        grid_num: ``[nx, ny, nz]`` points per axis, each >= 0 (default ``[1, 1, 1]``).
        spacing: Spacing per axis in metres (default ``[1.0, 1.0, 1.0]``).
        offset: World position of index ``[0, 0, 0]`` (default: the origin).
        func: Callback receiving ``grid_index`` (``[ix, iy, iz]``) and ``world_pos``
            (``[x, y, z]``, metres) positionally, then ``**args``.
        args: Extra keyword arguments for ``func``.

    Raises:
        ValueError: If ``grid_num`` is not three non-negative integers, or as
            :func:`grid_to_world` for ``spacing`` and ``offset``.
    """
    counts = [1, 1, 1] if grid_num is None else list(grid_num)
    if len(counts) != 3 or not all(
        isinstance(n, numbers.Integral) and not isinstance(n, bool) and n >= 0 for n in counts
    ):
        raise ValueError(f"grid_num: expected 3 integers >= 0, got {grid_num!r}")
    step, origin = _grid_frame([1.0, 1.0, 1.0] if spacing is None else spacing, offset)
    if func is None:
        return
    extra = dict(args or {})
    nx, ny, nz = (int(n) for n in counts)
    for ix in range(nx):
        for iy in range(ny):
            for iz in range(nz):
                index = [ix, iy, iz]
                func(index, (origin + np.array(index) * step).tolist(), **extra)


def _as_3d(values: Any, z: float) -> Any:
    """``[a, b]`` as ``[a, b, z]``; anything else unchanged (checked by the caller)."""
    if isinstance(values, (list, tuple, np.ndarray)) and len(values) == 2:
        return [*list(values), z]
    return values


def _grid_frame(spacing: float | Vector, offset: Vector | None) -> tuple[np.ndarray, np.ndarray]:
    step = normalize_vector_param(_as_3d(spacing, 1.0), "spacing", 3)
    if not (step > 0).all():
        raise ValueError(f"spacing: expected values > 0, got {spacing!r}")
    origin = (
        np.zeros(3) if offset is None else normalize_vector_param(_as_3d(offset, 0.0), "offset", 3)
    )
    return step, origin
