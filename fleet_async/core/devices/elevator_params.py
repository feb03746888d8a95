"""Elevator spawn parameters and the enums of its state machine (names as the reference's)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.base.types import coerce_enum

__all__ = [
    "ElevatorParams",
    "ElevatorRequestPolicy",
    "ElevatorRequestResult",
    "ElevatorState",
]


class ElevatorState(str, Enum):
    """Where an elevator is in its cycle.

    IDLE: standing at a floor. MOVING: travelling to ``target_floor``. ARRIVED: it reached a
    floor at the end of the step that just ran; it turns IDLE one step later (or MOVING, when
    a queued trip starts then).
    """

    IDLE = "idle"
    MOVING = "moving"
    ARRIVED = "arrived"


class ElevatorRequestPolicy(str, Enum):
    """What ``request_floor`` does with a request while the elevator is busy (moving, or with
    trips queued).

    REJECT: refuse it. REPLACE_NEXT: it replaces the trips queued after the current one.
    QUEUE: it is served after the trips before it, in request order. The cabin is never
    redirected mid-trip.
    """

    REJECT = "reject"
    REPLACE_NEXT = "replace_next"
    QUEUE = "queue"


class ElevatorRequestResult(str, Enum):
    """Outcome of ``request_floor``."""

    ACCEPTED = "accepted"
    QUEUED = "queued"
    REPLACED = "replaced"
    REJECTED = "rejected"


def _number(value: Any, name: str, minimum: float, strict: bool) -> float:
    ok = (
        isinstance(value, (int, float))
        and not isinstance(value, bool)
        and math.isfinite(value)
        and (value > minimum if strict else value >= minimum)
    )
    if not ok:
        raise ValueError(
            f"{name}: expected a finite number {'>' if strict else '>='} {minimum}, got {value!r}"
        )
    return float(value)


def _pair(value: Any, name: str) -> list[float]:
    if not (
        isinstance(value, (list, tuple))
        and len(value) == 2
        and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in value
        )
    ):
        raise ValueError(f"{name}: expected [x, y] (m), got {value!r}")
    return [float(value[0]), float(value[1])]


@dataclass
class ElevatorParams(AgentSpawnParams):
    """Spawn parameters of an Elevator (AgentSpawnParams plus the lift's own fields).

    The lift is a platform whose top surface stands at the current floor's height: the pose
    gives its centre (x, y) and yaw; its z is taken from ``initial_floor``. Without
    ``visual_shape`` / ``collision_shape`` the platform is a box of ``platform_size`` x
    ``platform_thickness`` under that surface.

    Attributes:
        floors: Floor name -> height of the platform's top at that floor (m). Required.
        initial_floor: Floor the lift starts at (default: the first one).
        request_policy: "reject" (default), "replace_next" or "queue" (``request_floor``).
        speed: Platform speed, m/s (a trip of h metres takes ``h / speed`` seconds).
        platform_size: [x, y] of the platform, m.
        platform_thickness: m.
        cabin_height: How high above the platform an object's base may be to ride along, m.
        landing_offset: [x, y] in the lift's frame where robots wait for it and leave it to, at
            every floor (default: half a platform plus 0.75 m towards -x).
        landings: Floor name -> [x, y] landing for that floor (overrides ``landing_offset``).
        rgba_color: Colour of the default platform.
    """

    use_fixed_base: bool = True
    floors: dict[str, float] | None = None
    initial_floor: str = ""
    request_policy: ElevatorRequestPolicy = ElevatorRequestPolicy.REJECT
    speed: float = 1.0
    platform_size: list[float] = field(default_factory=lambda: [1.6, 1.6])
    platform_thickness: float = 0.1
    cabin_height: float = 2.5
    landing_offset: list[float] | None = None
    landings: dict[str, list[float]] = field(default_factory=dict)
    rgba_color: list[float] = field(default_factory=lambda: [0.6, 0.62, 0.66, 1.0])

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.floors, dict) or not self.floors:
            raise ValueError(
                f"ElevatorParams.floors: expected a mapping {{floor name: height (m)}} with at "
                f"least one floor, got {self.floors!r}"
            )
        self.floors = {
            str(name): _number(h, f"ElevatorParams.floors[{name!r}]", -math.inf, strict=True)
            for name, h in self.floors.items()
        }
        if not self.initial_floor:
            self.initial_floor = next(iter(self.floors))
        if self.initial_floor not in self.floors:
            raise ValueError(
                f"ElevatorParams.initial_floor: {self.initial_floor!r} is not a floor; floors: "
                f"{list(self.floors)}"
            )
        self.request_policy = coerce_enum(
            ElevatorRequestPolicy, self.request_policy, "ElevatorParams.request_policy"
        )
        self.speed = _number(self.speed, "ElevatorParams.speed", 0.0, strict=True)
        self.platform_size = _pair(self.platform_size, "ElevatorParams.platform_size")
        if min(self.platform_size) <= 0:
            raise ValueError(
                f"ElevatorParams.platform_size: expected sizes > 0, got {self.platform_size!r}"
            )
        self.platform_thickness = _number(
            self.platform_thickness, "ElevatorParams.platform_thickness", 0.0, strict=True
        )
        self.cabin_height = _number(self.cabin_height, "ElevatorParams.cabin_height", 0.0, True)
        if self.landing_offset is None:
            self.landing_offset = [-(self.platform_size[0] / 2 + 0.75), 0.0]
        self.landing_offset = _pair(self.landing_offset, "ElevatorParams.landing_offset")
        for name in self.landings:
            if name not in self.floors:
                raise ValueError(
                    f"ElevatorParams.landings: {name!r} is not a floor; floors: {list(self.floors)}"
                )
        self.landings = {
            name: _pair(v, f"ElevatorParams.landings[{name!r}]")
            for name, v in self.landings.items()
        }

    @classmethod
    def from_dict(cls, config: dict[str, Any], *, source: str | None = None) -> ElevatorParams:
        """Build from a mapping (``pose`` + ``yaw`` accepted, as for agents)."""
        params = super().from_dict(config, source=source)
        assert isinstance(params, ElevatorParams)
        return params
