"""AgentSpawnParams: what it takes to create an Agent (IKParams, its IK part, lives with the
solver in ``motion/ik.py`` and is re-exported here)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from fleet_async.core.base.config_utils import dataclass_from_dict
from fleet_async.core.base.types import MotionMode, coerce_enum
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.collision.safety_params import SafetyFieldParams
from fleet_async.core.motion.ik import IKParams

__all__ = ["AgentSpawnParams", "IKParams"]


@dataclass
class AgentSpawnParams(SimObjectSpawnParams):
    """Parameters for spawning an Agent: a mesh robot, a URDF robot or a virtual agent.

    Give ``visual_shape`` / ``collision_shape`` for a mesh robot, ``urdf_path`` (a file or a
    model name such as "mobile_robot" or "panda") for a URDF robot, or neither for a virtual
    agent (no geometry, no collision).

    Attributes:
        mass: kg, as for any object (0.0: kinematic, every URDF link made massless); for a
            URDF robot also None: the URDF's own link masses, ``Agent.from_urdf``'s default
            (the agent's ``mass`` is then their total).
        urdf_path: URDF file or model name.
        motion_mode: Default base controller when ``controller`` names none (deprecated
            shortcut; prefer ``controller="omni"`` / ``"differential"``).
        use_fixed_base: The base never moves (arms on a table).
        ik_params: IK settings for arms.
        controller: Controller selector or configuration (see ``Agent``).
        plugins: Per-agent plugin entries ``{"type": "battery", "config": {...}}``.
        safety_field: Protective and warning fields (``SafetyFieldParams``, a mapping of
            its fields, or True for the defaults); None (the default) for none.
    """

    # Widened for URDF robots only: shape-based and virtual agents are refused a None mass in
    # _checked_mass, so the body-making code that reads SimObjectSpawnParams.mass gets a float.
    mass: float | None = 0.0  # type: ignore[assignment]
    urdf_path: str | None = None
    motion_mode: MotionMode = MotionMode.DIFFERENTIAL
    use_fixed_base: bool = False
    ik_params: IKParams | None = None
    controller: Any = None
    plugins: list[dict[str, Any]] | None = None
    safety_field: SafetyFieldParams | None = None
    name_required_in_config: ClassVar[bool] = False  # the reference's agent configs have none

    def __post_init__(self) -> None:
        super().__post_init__()
        self.motion_mode = coerce_enum(MotionMode, self.motion_mode, "AgentSpawnParams.motion_mode")
        if self.urdf_path is not None and not isinstance(self.urdf_path, str):
            raise ValueError(
                f"AgentSpawnParams.urdf_path: expected a path or model name, got {self.urdf_path!r}"
            )
        if isinstance(self.ik_params, dict):
            self.ik_params = dataclass_from_dict(IKParams, self.ik_params, section="ik_params")
        self.safety_field = SafetyFieldParams.coerce(
            self.safety_field, "AgentSpawnParams.safety_field"
        )
        if self.plugins is not None and not (
            isinstance(self.plugins, list) and all(isinstance(e, dict) for e in self.plugins)
        ):
            raise ValueError(
                f"AgentSpawnParams.plugins: expected a list of mappings, got {self.plugins!r}"
            )

    def _keeps_own_masses(self) -> bool:
        return self.kind == "urdf"

    def _checked_mass(self) -> float:
        if self.mass is None:
            raise ValueError(
                f"{type(self).__name__}.mass: None (keep a URDF's own masses) needs urdf_path; "
                f"this {self.kind} agent has none: give a mass in kg (0.0: kinematic)"
            )
        return super()._checked_mass()

    @classmethod
    def from_dict(cls, config: dict[str, Any], *, source: str | None = None) -> AgentSpawnParams:
        """Build from a programmatic or YAML-style mapping (``pose`` + ``yaw`` accepted)."""
        params = super().from_dict(config, source=source)
        assert isinstance(params, AgentSpawnParams)
        return params

    @property
    def kind(self) -> str:
        """ "urdf", "mesh" or "virtual"."""
        if self.urdf_path:
            return "urdf"
        if self.visual_shape is not None or self.collision_shape is not None:
            return "mesh"
        return "virtual"
