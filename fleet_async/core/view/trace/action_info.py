"""What a trace says about an action beyond its class: its goal, path, object and duration.

The viewer's timeline names what each action was for ("PickAction tote_A1_0 at (2.5, 3.2)"),
and draws the selected robot's current goal and path, from these fields of the
``action_started`` / ``action_ended`` events. They are read from the action's public fields
by name (any action class that has them gets them), so this module imports no action class.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Iterable

__all__ = ["MAX_PATH_POINTS", "describe_end", "describe_start"]

MAX_PATH_POINTS = 64
"""Waypoints kept of a move's path (the first ones and the goal): an event stays small."""


def _xy(value: Any) -> list[float] | None:
    """[x, y] of a Pose, or of an [x, y, ...] sequence, rounded to mm; None otherwise."""
    position = getattr(value, "position", value)
    try:
        x, y = float(position[0]), float(position[1])
    except (TypeError, IndexError, ValueError, KeyError):
        return None
    return [round(x, 3), round(y, 3)]


def _target(target: Any, objects: Iterable[Any]) -> Any:
    """The body ``target`` names: a body handle, or a PyBullet body id; None otherwise."""
    if target is None:
        return None
    if getattr(target, "object_id", None) is not None:
        return target
    if isinstance(target, int):
        return next((o for o in objects if getattr(o, "body_id", None) == target), None)
    return None


def describe_start(action: Any, objects: Iterable[Any]) -> dict[str, Any]:
    """The ``action_started`` data beyond ``action``: ``goal`` [x, y] (m, world frame),
    ``path`` (the move's waypoints as [x, y]), ``object`` (the object id it picks or drops),
    ``duration`` (s) and ``label`` (a wait's ``action_type``, e.g. ``charge``); each only when
    the action has it.

    Args:
        action: The action that started.
        objects: The simulation's bodies, to turn a PyBullet body id into an object id.
    """
    data: dict[str, Any] = {}
    waypoints = getattr(getattr(action, "path", None), "waypoints", None)
    if waypoints:
        points = [p for p in (_xy(w) for w in waypoints) if p is not None]
        if len(points) > MAX_PATH_POINTS:
            points = [*points[: MAX_PATH_POINTS - 1], points[-1]]
        if points:
            data["path"] = points
            data["goal"] = points[-1]
    for field in ("drop_pose", "target_position"):
        goal = _xy(getattr(action, field, None))
        if goal is not None:
            data["goal"] = goal
            break
    target = _target(getattr(action, "target_object_id", None), objects)
    if target is not None:
        data["object"] = int(target.object_id)
        if "goal" not in data and hasattr(target, "get_pose"):
            data["goal"] = _xy(target.get_pose())
    duration = getattr(action, "duration", None)
    if isinstance(duration, (int, float)) and not isinstance(duration, bool):
        data["duration"] = float(duration)
    label = getattr(action, "action_type", None)
    if isinstance(label, str):
        data["label"] = label
    return data


def describe_end(action: Any) -> dict[str, Any]:
    """The ``action_ended`` data beyond ``action`` and ``status``: ``object``, the object id
    a pick picked or a drop dropped, when there is one."""
    for field in ("picked_object", "dropped_object"):
        obj = getattr(action, field, None)
        if obj is not None and getattr(obj, "object_id", None) is not None:
            return {"object": int(obj.object_id)}
    return {}
