"""Enumerations shared across the simulator.

Every enum derives from ``str`` so that YAML values (``"omnidirectional"``) and enum members
compare equal and serialise as plain strings. Use :func:`coerce_enum` to turn user input into a
member with an error that names the field and the accepted values.
"""

from __future__ import annotations

from enum import Enum
from typing import TypeVar

__all__ = [
    "ActionStatus",
    "CollisionDetectionMethod",
    "CollisionMode",
    "ControllerMode",
    "DoorState",
    "DropPhase",
    "MotionMode",
    "MovementDirection",
    "PickPhase",
    "PosePhase",
    "SpatialHashCellSizeMode",
    "coerce_enum",
]


class MotionMode(str, Enum):
    """How a mobile base moves: holonomic (any direction) or differential (rotate, then drive)."""

    OMNIDIRECTIONAL = "omnidirectional"
    DIFFERENTIAL = "differential"


class PosePhase(str, Enum):
    """Phase of a pose-following controller: rotating in place, or driving straight."""

    ROTATE = "rotate"
    FORWARD = "forward"


class MovementDirection(str, Enum):
    """Which way a differential robot faces while following a path.

    FORWARD faces the travel direction, BACKWARD keeps its back to it, AUTO picks BACKWARD when
    the goal is more than 90 degrees behind the robot.
    """

    FORWARD = "forward"
    BACKWARD = "backward"
    AUTO = "auto"


class ActionStatus(str, Enum):
    """Execution status of an Action."""

    NOT_STARTED = "not_started"
    IN_PROGRESS = "in_progress"
    COMPLETED = "completed"
    FAILED = "failed"
    CANCELLED = "cancelled"


class SpatialHashCellSizeMode(str, Enum):
    """How the broad-phase spatial hash picks its cell size."""

    CONSTANT = "constant"
    AUTO_ADAPTIVE = "auto_adaptive"
    AUTO_INITIAL = "auto_initial"


class DoorState(str, Enum):
    """Operational state of a door device."""

    CLOSED = "closed"
    OPENING = "opening"
    OPEN = "open"
    CLOSING = "closing"


class ControllerMode(str, Enum):
    """State of a kinematic controller: idle, following cmd_vel, or tracking a pose/path."""

    IDLE = "idle"
    VELOCITY = "velocity"
    POSE = "pose"


class CollisionMode(str, Enum):
    """How one object takes part in collision detection.

    NORMAL_3D: full 3D AABB overlap. NORMAL_2D: Z ignored (ground vehicles). STATIC: registered
    once and never refreshed (walls, shelves). DISABLED: no AABB, no grid, no PyBullet contact.
    """

    NORMAL_3D = "normal_3d"
    NORMAL_2D = "normal_2d"
    STATIC = "static"
    DISABLED = "disabled"


class CollisionDetectionMethod(str, Enum):
    """Narrow-phase method: distance queries, physics contacts, or both by body kind."""

    CLOSEST_POINTS = "closest_points"
    CONTACT_POINTS = "contact_points"
    HYBRID = "hybrid"


class PickPhase(str, Enum):
    """Phases of a PickAction."""

    INIT = "init"
    APPROACHING = "approaching"
    MOVING_TO_PICK = "moving_to_pick"
    PICKING = "picking"
    RETREATING = "retreating"


class DropPhase(str, Enum):
    """Phases of a DropAction."""

    INIT = "init"
    APPROACHING = "approaching"
    MOVING_TO_DROP = "moving_to_drop"
    DROPPING = "dropping"
    RETREATING = "retreating"


E = TypeVar("E", bound=Enum)


def coerce_enum(enum_cls: type[E], value: object, field: str) -> E:
    """Return ``value`` as a member of ``enum_cls``.

    Accepts a member, its value (case-insensitive string) or its name.

    Raises:
        ValueError: naming ``field``, the bad value and the accepted values.
    """
    if isinstance(value, enum_cls):
        return value
    if isinstance(value, str):
        key = value.strip().lower()
        for member in enum_cls:
            if str(member.value).lower() == key or member.name.lower() == key:
                return member
    accepted = ", ".join(repr(m.value) for m in enum_cls)
    raise ValueError(
        f"{field}: {value!r} is not a valid {enum_cls.__name__}; expected one of {accepted}"
    )
