"""Small kinematic, PyBullet-lookup and grid helpers shared across the simulator.

Frames and units: positions are metres in the world frame unless stated, angles are radians,
quaternions are ``(x, y, z, w)`` like PyBullet. Grids are axis-aligned: grid index ``i`` on an
axis sits at ``offset + i * spacing`` on that axis.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import pybullet as p

from fleet_async.core.geometry.limits import Pose, rotate_vector

__all__ = [
    "body_to_world_velocity_2d",
    "body_to_world_velocity_3d",
    "calculate_offset_pose",
    "find_nearest",
    "grid_execution",
    "grid_to_world",
    "grid_to_world_2d",
    "normalize_vector_param",
    "resolve_joint_index",
    "resolve_link_index",
    "world_to_grid",
    "world_to_grid_2d",
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
    expected = f"{param_name}: expected a number or {dim} numbers, got {value!r}"
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nesting
        raise ValueError(expected) from exc
    if raw.dtype.kind not in "iuf":  # rejects bools, strings and arbitrary objects
        raise ValueError(expected)
    arr = np.full(dim, float(raw)) if raw.ndim == 0 else raw.astype(np.float64)
    if arr.shape != (dim,):
        raise ValueError(expected)
    if not np.isfinite(arr).all():
        raise ValueError(f"{param_name}: expected finite numbers, got {value!r}")
    return arr


def resolve_link_index(body_id: int, link: int | str, physics_client_id: int = 0) -> int:
    """Resolve a link name (or index) of a PyBullet body to its link index.

    The base is index -1. A name matches the base link's own name, then each joint's child
    link; ``"base_link"`` also means the base when no link of that name exists.

    Args:
        body_id: PyBullet body unique id.
        link: Link index (passed through after a range check) or link name.
        physics_client_id: PyBullet client the body lives in.

    Returns:
        The link index, -1 for the base.

    Raises:
        ValueError: If an index is outside ``[-1, numJoints)`` or the name is unknown (the
            message lists the body's link names).
        TypeError: If ``link`` is neither an int nor a str.
    """
    count, base = _body_info(body_id, physics_client_id)
    if not isinstance(link, str):
        return _checked_index(link, -1, count, "link", body_id)
    names = [base] + [
        p.getJointInfo(body_id, i, physicsClientId=physics_client_id)[12].decode("utf-8")
        for i in range(count)
    ]
    if link in names:
        return names.index(link) - 1
    if link == "base_link":
        return -1
    raise ValueError(f"Body {body_id} has no link named {link!r}; known links: {names}")


def resolve_joint_index(body_id: int, joint: int | str, physics_client_id: int = 0) -> int:
    """Resolve a joint name (or index) of a PyBullet body to its joint index.

    Args:
        body_id: PyBullet body unique id.
        joint: Joint index (passed through after a range check) or joint name.
        physics_client_id: PyBullet client the body lives in.

    Returns:
        The joint index, in ``[0, numJoints)``.

    Raises:
        ValueError: If an index is outside ``[0, numJoints)`` or the name is unknown (the
            message lists the body's joint names).
        TypeError: If ``joint`` is neither an int nor a str.
    """
    count, _ = _body_info(body_id, physics_client_id)
    if not isinstance(joint, str):
        return _checked_index(joint, 0, count, "joint", body_id)
    names = [
        p.getJointInfo(body_id, i, physicsClientId=physics_client_id)[1].decode("utf-8")
        for i in range(count)
    ]
    if joint in names:
        return names.index(joint)
    raise ValueError(f"Body {body_id} has no joint named {joint!r}; known joints: {names}")


def _body_info(body_id: int, client: int) -> tuple[int, str]:
    """Return the body's joint count and base link name; ValueError if there is no such body."""
    count = p.getNumJoints(body_id, physicsClientId=client)  # raises if not connected
    try:
        info = p.getBodyInfo(body_id, physicsClientId=client)
    except p.error:
        # Bodies made by one createMultiBody(batchPositions=...) call exist on PyBullet's
        # server, but its client-side cache only learns of the last one; refresh it once.
        p.syncBodyInfo(physicsClientId=client)
        try:
            info = p.getBodyInfo(body_id, physicsClientId=client)
        except p.error as exc:
            raise ValueError(f"No body with id {body_id} in physics client {client}") from exc
    return count, info[0].decode("utf-8")


def _checked_index(index: object, low: int, count: int, kind: str, body_id: int) -> int:
    if isinstance(index, bool) or not isinstance(index, numbers.Integral):
        raise TypeError(f"{kind}: expected an int index or a name, got {index!r}")
    value = int(index)
    if not low <= value < count:
        raise ValueError(
            f"{kind} index {value} out of range [{low}, {count}) for body {body_id} "
            f"with {count} joints"
        )
    return value


def calculate_offset_pose(
    target_position: Vector,
    current_position: Vector,
    offset: float,
    keep_height: bool = True,
) -> Pose:
    """Pose ``offset`` metres short of a target, facing it (approach, pick and drop poses).

    The pose lies on the XY line from the target toward ``current_position``, with the yaw that
    faces the target (roll and pitch 0). With ``offset == 0`` it is at the target, still facing
    the way it was approached. If the two positions coincide in XY there is no direction: the
    pose is at the target with yaw 0.

    Args:
        target_position: ``[x, y, z]`` of the target (world frame, metres).
        current_position: ``[x, y, z]`` of the robot (world frame, metres).
        offset: Distance from the target in the XY plane, metres (>= 0).
        keep_height: Use ``current_position``'s z if True, else the target's z.

    Returns:
        The offset pose.

    Raises:
        ValueError: If a position is not 3 finite numbers or ``offset`` is negative or not
            finite.
    """
    target = _vector(target_position, "target_position", 3)
    current = _vector(current_position, "current_position", 3)
    real = isinstance(offset, numbers.Real) and not isinstance(offset, bool)
    if not (real and math.isfinite(offset) and offset >= 0):
        raise ValueError(f"offset: expected a finite number >= 0 (metres), got {offset!r}")
    dx, dy = float(current[0] - target[0]), float(current[1] - target[1])
    distance = math.hypot(dx, dy)
    z = float(current[2] if keep_height else target[2])
    if distance == 0.0:
        return Pose.from_euler(float(target[0]), float(target[1]), z)
    ux, uy = dx / distance, dy / distance
    x, y = float(target[0]) + offset * ux, float(target[1]) + offset * uy
    return Pose.from_euler(x, y, z, yaw=math.atan2(-uy, -ux))


def world_to_grid(pos: Vector, spacing: float | Vector, offset: Vector | None = None) -> list[int]:
    """Convert a world position to the nearest 3-D grid index.

    Args:
        pos: ``[x, y, z]`` in metres.
        spacing: Grid spacing per axis (or one value for all), metres, each > 0.
        offset: World position of grid index ``[0, 0, 0]`` (default: the origin).

    Returns:
        ``[ix, iy, iz]``, each ``round((pos - offset) / spacing)`` with halves rounded up.

    Raises:
        ValueError: If a vector has the wrong length, or a spacing is not > 0.
    """
    position = _vector(pos, "pos", 3)
    step, origin = _grid_frame(spacing, offset)
    return [math.floor(v + 0.5) for v in ((position - origin) / step).tolist()]


def grid_to_world(
    grid: Sequence[int], spacing: float | Vector, offset: Vector | None = None
) -> list[float]:
    """Convert a 3-D grid index to its world position.

    Args:
        grid: ``[ix, iy, iz]``.
        spacing: Grid spacing per axis (or one value for all), metres, each > 0.
        offset: World position of grid index ``[0, 0, 0]`` (default: the origin).

    Returns:
        ``[x, y, z]`` in metres: ``offset + grid * spacing``.

    Raises:
        ValueError: If a vector has the wrong length, or a spacing is not > 0.
    """
    index = _vector(grid, "grid", 3)
    step, origin = _grid_frame(spacing, offset)
    return (origin + index * step).tolist()


def world_to_grid_2d(pos: Vector, spacing: float | Vector) -> list[int]:
    """2-D form of :func:`world_to_grid`: ``[x, y]`` and ``[sx, sy]`` to ``[ix, iy]``."""
    xy = _vector(pos, "pos", 2)
    sxy = normalize_vector_param(spacing, "spacing", 2)
    return world_to_grid([xy[0], xy[1], 0.0], [sxy[0], sxy[1], 1.0])[:2]


def grid_to_world_2d(grid: Sequence[int], spacing: float | Vector) -> list[float]:
    """2-D form of :func:`grid_to_world`: ``[ix, iy]`` and ``[sx, sy]`` to ``[x, y]``."""
    ij = _vector(grid, "grid", 2)
    sxy = normalize_vector_param(spacing, "spacing", 2)
    return grid_to_world([ij[0], ij[1], 0], [sxy[0], sxy[1], 1.0])[:2]


def grid_execution(
    grid_num: Sequence[int] | None = None,
    spacing: float | Vector | None = None,
    offset: Vector | None = None,
    func: Callable[..., Any] | None = None,
    args: Mapping[str, Any] | None = None,
) -> None:
    """Call ``func(grid_index, world_pos, **args)`` at every point of a 3-D grid.

    Points are visited with X varying fastest, then Y, then Z: for ``grid_num=[2, 2, 1]`` the
    order is ``[0,0,0], [1,0,0], [0,1,0], [1,1,0]``. With ``func=None`` nothing is called.

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
    for iz in range(nz):
        for iy in range(ny):
            for ix in range(nx):
                index = [ix, iy, iz]
                func(index, (origin + np.array(index) * step).tolist(), **extra)


def find_nearest(
    objects: Iterable[Any],
    position: Vector,
    search_radius: float,
    predicate: Callable[[Any], bool] | None = None,
    exclude: Any | None = None,
    use_2d: bool = False,
) -> Any | None:
    """Return the nearest object within ``search_radius`` of ``position``, or None.

    Args:
        objects: Objects exposing ``get_pose().position`` (world frame, metres).
        position: ``[x, y, z]`` reference point in the world frame.
        search_radius: Maximum distance in metres (inclusive, >= 0; ``math.inf`` for no limit).
        predicate: Keeps only objects for which it returns True; called only on objects that
            are in range and nearer than the best match so far.
        exclude: One object to skip, compared by identity (typically the caller itself).
        use_2d: Measure distance in the XY plane only.

    Returns:
        The nearest matching object; among equally near ones, the first in iteration order.

    Raises:
        ValueError: If ``search_radius`` is negative or NaN, or ``position`` is not 3 numbers.
    """
    if not search_radius >= 0:
        raise ValueError(f"search_radius: expected a number >= 0 (metres), got {search_radius!r}")
    px, py, pz = _vector(position, "position", 3).tolist()
    best, best_distance = None, float(search_radius)
    for obj in objects:
        if obj is exclude:
            continue
        q = obj.get_pose().position
        dz = 0.0 if use_2d else float(q[2]) - pz
        distance = math.sqrt((float(q[0]) - px) ** 2 + (float(q[1]) - py) ** 2 + dz * dz)
        # "not <=" also skips NaN distances; an equal distance keeps the earlier object.
        if not distance <= best_distance or (best is not None and distance == best_distance):
            continue
        if predicate is None or predicate(obj):
            best, best_distance = obj, distance
    return best


def _vector(value: Any, name: str, dim: int) -> np.ndarray:
    """Like normalize_vector_param, but a scalar is an error: positions are never broadcast."""
    if isinstance(value, (numbers.Number, np.generic, str)) or getattr(value, "ndim", 1) == 0:
        raise ValueError(f"{name}: expected {dim} numbers, got {value!r}")
    return normalize_vector_param(value, name, dim)


def _grid_frame(spacing: float | Vector, offset: Vector | None) -> tuple[np.ndarray, np.ndarray]:
    step = normalize_vector_param(spacing, "spacing", 3)
    if not (step > 0).all():
        raise ValueError(f"spacing: expected values > 0, got {spacing!r}")
    origin = np.zeros(3) if offset is None else normalize_vector_param(offset, "offset", 3)
    return step, origin
