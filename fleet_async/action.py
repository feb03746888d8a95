"""Robot actions: move, wait, pick / drop, joint targets and end-effector poses.

The reference API's ``action`` module: a thin facade over the modules of the core that own these
names, so a pybullet_fleet script ports by renaming its import (``pybullet_fleet.action``
becomes ``fleet_async.action``). Nothing in fleet_async imports this module.
"""

from __future__ import annotations

from fleet_async.core.actions.action import (
    DEFAULT_EE_TOLERANCE,
    DEFAULT_JOINT_TOLERANCE,
    DEFAULT_MAX_FORCE,
    DEFAULT_MOVE_SKIP_THRESHOLD,
    Action,
    MoveAction,
    WaitAction,
)
from fleet_async.core.actions.arm_actions import JointAction, PoseAction
from fleet_async.core.actions.pick_drop import DropAction, PickAction
from fleet_async.core.base.types import DropPhase, PickPhase

__all__ = [
    "DEFAULT_EE_TOLERANCE",
    "DEFAULT_JOINT_TOLERANCE",
    "DEFAULT_MAX_FORCE",
    "DEFAULT_MOVE_SKIP_THRESHOLD",
    "Action",
    "DropAction",
    "DropPhase",
    "JointAction",
    "MoveAction",
    "PickAction",
    "PickPhase",
    "PoseAction",
    "WaitAction",
]
