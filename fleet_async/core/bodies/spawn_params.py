"""SimObjectSpawnParams: everything needed to create one SimObject."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

from fleet_async.core.base.config_utils import dataclass_from_dict
from fleet_async.core.base.types import CollisionMode, coerce_enum
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.pose_config import pose_from_config
from fleet_async.core.world.shapes import ShapeParams

__all__ = ["SimObjectSpawnParams"]

logger = logging.getLogger(__name__)


@dataclass
class SimObjectSpawnParams:
    """Parameters for spawning a SimObject.

    Attributes:
        visual_shape: Visual geometry, or None for an invisible body.
        collision_shape: Collision geometry, or None for no collision shape.
        initial_pose: Pose in the world frame (default: origin, identity).
        mass: kg; 0.0 is kinematic (moved only by the simulator), > 0 is dynamic when physics is on.
        pickable: Whether pick actions may pick this object.
        name: Human-readable name; duplicates allowed (use ``object_id`` for identity).
        visual_frame_pose: Visual shape offset in the body frame (overrides the shape's own).
        collision_frame_pose: Collision shape offset in the body frame (overrides the shape's own).
        collision_mode: How the object takes part in collision detection.
        user_data: Free-form metadata.
    """

    visual_shape: ShapeParams | None = None
    collision_shape: ShapeParams | None = None
    initial_pose: Pose = field(default_factory=lambda: Pose([0.0, 0.0, 0.0]))
    mass: float = 0.0
    pickable: bool = True
    name: str | None = None
    visual_frame_pose: Pose | None = None
    collision_frame_pose: Pose | None = None
    collision_mode: CollisionMode = CollisionMode.NORMAL_3D
    user_data: dict[str, Any] = field(default_factory=dict)
    name_required_in_config: ClassVar[bool] = True
    """Whether :meth:`from_dict` requires ``name`` (the reference API: "name (str, required)";
    agents' configs may leave it out)."""

    def __post_init__(self) -> None:
        # Spawning loops build one of these per object: the common, already-typed values pass
        # with a type check each; anything else goes through the converting checks.
        cls_name = type(self).__name__
        for name in ("visual_shape", "collision_shape"):
            value = getattr(self, name)
            if value is None or type(value) is ShapeParams:
                continue
            if isinstance(value, dict):
                setattr(self, name, ShapeParams.from_dict(value))
            elif not isinstance(value, ShapeParams):
                raise ValueError(
                    f"{cls_name}.{name}: expected ShapeParams, a mapping or None, got {value!r}"
                )
        if (
            type(self.initial_pose) is not Pose
            or self.visual_frame_pose is not None
            or (self.collision_frame_pose is not None)
        ):
            for name in ("initial_pose", "visual_frame_pose", "collision_frame_pose"):
                value = getattr(self, name)
                if value is not None and not isinstance(value, Pose):
                    setattr(self, name, pose_from_config(value, field_name=f"{cls_name}.{name}"))
            if self.initial_pose is None:
                raise ValueError(f"{cls_name}.initial_pose: expected a Pose, got None")
        mass = self.mass
        if (type(mass) is not float or not (0.0 <= mass < math.inf)) and (
            mass is not None or not self._keeps_own_masses()
        ):
            self.mass = self._checked_mass()
        if type(self.collision_mode) is not CollisionMode:
            self.collision_mode = coerce_enum(
                CollisionMode, self.collision_mode, f"{cls_name}.collision_mode"
            )
        if self.name is not None and not isinstance(self.name, str):
            raise ValueError(f"{cls_name}.name: expected a string or None, got {self.name!r}")
        if type(self.user_data) is not dict and not isinstance(self.user_data, dict):
            raise ValueError(f"{cls_name}.user_data: expected a mapping, got {self.user_data!r}")

    def _keeps_own_masses(self) -> bool:
        """Whether ``mass=None`` is allowed: the body's file gives the masses (not here)."""
        return False

    def _checked_mass(self) -> float:
        """``mass`` as a float, or a ValueError naming it (the slow path of the check)."""
        mass = self.mass
        if (
            isinstance(mass, bool)
            or not isinstance(mass, (int, float))
            or not math.isfinite(mass)
            or mass < 0
        ):
            raise ValueError(
                f"{type(self).__name__}.mass: expected a finite number >= 0 (kg), got {mass!r}"
            )
        return float(mass)

    @classmethod
    def from_dict(
        cls, config: dict[str, Any], *, source: str | None = None
    ) -> SimObjectSpawnParams:
        """Build from a programmatic or YAML-style mapping.

        Besides the field names, accepts ``pose: [x, y, z]`` with optional ``yaw`` (radians) as
        an alternative to ``initial_pose``; when both are given, ``initial_pose`` takes
        precedence (with a warning). Shape entries may be ShapeParams or mappings.

        Raises:
            ValueError: if ``name`` is missing (SimObjectSpawnParams only), for an unknown key
                (with the nearest valid one) or a bad value.
        """
        where = f"{source}: " if source is not None else ""
        if not isinstance(config, dict):
            raise ValueError(f"{where}{cls.__name__}.from_dict: expected a mapping, got {config!r}")
        config = dict(config)
        if cls.name_required_in_config and config.get("name") is None:
            raise ValueError(
                f"{where}{cls.__name__}.from_dict: missing required 'name' field "
                f"(keys given: {sorted(config)})"
            )
        pose, yaw = config.pop("pose", None), config.pop("yaw", None)
        pose_keys = ("pose", "yaw")
        if "initial_pose" in config:
            if pose is not None or yaw is not None:
                logger.warning(
                    "%s%s: both 'initial_pose' and 'pose'/'yaw' given; initial_pose takes "
                    "precedence, pose=%r yaw=%r ignored",
                    where,
                    cls.__name__,
                    pose,
                    yaw,
                )
        elif pose is not None or yaw is not None:
            config["initial_pose"] = pose_from_config(
                pose if pose is not None else [0.0, 0.0, 0.0], yaw, field_name="pose"
            )
        for name in ("visual_shape", "collision_shape"):
            if isinstance(config.get(name), dict):
                config[name] = ShapeParams.from_dict(config[name], source=source)
        return dataclass_from_dict(
            cls, config, source=source, section=cls.__name__, extra_keys=pose_keys
        )

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Names of the constructor fields (for config validation)."""
        return tuple(f.name for f in fields(cls) if f.init)
