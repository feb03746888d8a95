from __future__ import annotations

import pytest

from fleet_async import (
    ActionStatus,
    CollisionDetectionMethod,
    CollisionMode,
    ControllerMode,
    DoorState,
    DropPhase,
    MotionMode,
    MovementDirection,
    PickPhase,
    PosePhase,
    SpatialHashCellSizeMode,
)
from fleet_async.core.base.types import coerce_enum

EXPECTED = {
    MotionMode: ["omnidirectional", "differential"],
    PosePhase: ["rotate", "forward"],
    MovementDirection: ["forward", "backward", "auto"],
    ActionStatus: ["not_started", "in_progress", "completed", "failed", "cancelled"],
    SpatialHashCellSizeMode: ["constant", "auto_adaptive", "auto_initial"],
    DoorState: ["closed", "opening", "open", "closing"],
    ControllerMode: ["idle", "velocity", "pose"],
    CollisionMode: ["normal_3d", "normal_2d", "static", "disabled"],
    CollisionDetectionMethod: ["closest_points", "contact_points", "hybrid"],
    PickPhase: ["init", "approaching", "moving_to_pick", "picking", "retreating"],
    DropPhase: ["init", "approaching", "moving_to_drop", "dropping", "retreating"],
}


@pytest.mark.parametrize("enum_cls", list(EXPECTED), ids=lambda e: e.__name__)
def test_enum_values_match_reference_and_compare_as_strings(enum_cls):
    assert [m.value for m in enum_cls] == EXPECTED[enum_cls]
    first = next(iter(enum_cls))
    assert first == first.value  # str enums: YAML strings compare equal to members


def test_coerce_enum_accepts_member_value_and_name():
    assert coerce_enum(MotionMode, MotionMode.DIFFERENTIAL, "m") is MotionMode.DIFFERENTIAL
    assert coerce_enum(MotionMode, "Omnidirectional", "m") is MotionMode.OMNIDIRECTIONAL
    assert coerce_enum(CollisionMode, "NORMAL_2D", "m") is CollisionMode.NORMAL_2D


def test_coerce_enum_error_names_field_value_and_choices():
    with pytest.raises(
        ValueError, match=r"agent\.motion_mode: 'hover'.*'omnidirectional', 'differential'"
    ):
        coerce_enum(MotionMode, "hover", "agent.motion_mode")
    with pytest.raises(ValueError, match="3"):
        coerce_enum(MotionMode, 3, "m")
