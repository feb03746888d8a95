"""Where to stand to reach something, and what is nearest: the geometry of pick and drop.

Positions are metres in the world frame; yaw is radians counter-clockwise from +X.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Iterable
from typing import Any

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.vectors import Vector, strict_vector

__all__ = ["calculate_offset_pose", "find_nearest"]


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
    target = strict_vector(target_position, "target_position", 3)
    current = strict_vector(current_position, "current_position", 3)
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
    px, py, pz = strict_vector(position, "position", 3).tolist()
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
