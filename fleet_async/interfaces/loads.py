"""What a vehicle carries: the core's pick and drop actions for an order's load tasks.

A served vehicle picks and drops where it stands (at the node it reached): a pick attaches the
nearest pickable object within :data:`PICK_REACH` (the object named by the task's ``load_id``
when it gives one) without driving to it; a drop puts what it carries down where it stands, at
the height the load had when it was picked.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

from fleet_async.core.actions.action import Action
from fleet_async.core.actions.pick_drop import DropAction, PickAction
from fleet_async.core.geometry.pose import Pose
from fleet_async.interfaces.commands import Task
from fleet_async.interfaces.snapshot import VehicleLoad

__all__ = ["PICK_REACH", "load_action", "loads_of"]

PICK_REACH = 1.0
"""m: how far from the vehicle a pick looks for its load."""


def _distance_xy(a: Pose, b: Pose) -> float:
    return math.hypot(a.x - b.x, a.y - b.y)


def load_action(
    task: Task, agent: Any, objects: Iterable[Any], rest_heights: dict[int, float]
) -> Action | str:
    """The PickAction / DropAction for ``task`` (``"pick"`` or ``"drop"``), or why none.

    Args:
        task: The task.
        agent: The vehicle's robot.
        objects: Every object of the simulation (where a pick looks for its load).
        rest_heights: ``{object id: z}`` where loads stood when picked: a pick adds to it, a
            drop puts the load down at that height (else at the robot's own).
    """
    here = agent.get_pose()
    if task.kind == "drop":
        carried = list(agent.get_attached_objects())
        if not carried:
            return "the vehicle carries nothing to drop"
        z = rest_heights.pop(carried[0].object_id, here.z)
        where = Pose.from_yaw(here.x, here.y, z, here.yaw)
        return DropAction(drop_pose=where, use_approach=False, place_gently=True)
    load_id = task.params.get("load_id")
    candidates = [
        o
        for o in objects
        if getattr(o, "pickable", False)
        and not o.is_attached()
        and o is not agent
        and (load_id is None or o.name == load_id)
    ]
    if not candidates:
        return f"no pickable object named {load_id!r}" if load_id else "nothing to pick"
    target = min(candidates, key=lambda o: _distance_xy(o.get_pose(), here))
    away = _distance_xy(target.get_pose(), here)
    if away > PICK_REACH:
        return f"the load {target.name!r} is {away:.2f} m away (reach {PICK_REACH:g} m)"
    rest_heights[target.object_id] = target.get_pose().z
    return PickAction(target_object_id=target, use_approach=False, pick_offset=away)


def loads_of(agent: Any) -> tuple[VehicleLoad, ...]:
    """What ``agent`` carries: its attached objects, by name (their id when unnamed)."""
    loads = []
    for obj in agent.get_attached_objects():
        mass = getattr(obj, "mass", None)
        weight = float(mass) if isinstance(mass, (int, float)) and mass > 0 else None
        loads.append(VehicleLoad(obj.name or str(obj.object_id), weight))
    return tuple(loads)
