"""SafetyFieldParams: an agent's protective and warning fields (a safety scanner's fields).

A field is a rectangle in front of the robot along its direction of travel. Its depth ahead of
the footprint grows with the speed ``v`` the robot drives at (m/s):

    protective depth = v**2 / (2 * deceleration) + protective_margin
    warning depth    = protective depth + warning_margin

and it is as wide as the footprint across the direction of travel, plus ``side_margin`` on each
side. Something in the protective field stops the robot in that step; something in the
warning field (only) slows it to ``slow_factor`` of its speed (``collision/safety.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = ["SafetyFieldParams"]


def _positive(name: str, value: Any, allow_zero: bool = False) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"SafetyFieldParams.{name}: expected a number {bound}, got {value!r}")
    return float(value)


@dataclass
class SafetyFieldParams:
    """An agent's safety fields (off unless an agent is given some).

    Attributes:
        deceleration: Braking deceleration the protective field is sized for (m/s^2, > 0).
        protective_margin: Protective field depth ahead of the footprint at standstill (m).
        warning_margin: How far the warning field reaches beyond the protective field (m);
            0 for no warning field.
        side_margin: Extra width on each side of the footprint (m).
        slow_factor: Fraction of its speed a robot drives at while something is in its
            warning field (0 < f <= 1; 1: the warning field only reports).
        footprint: (length, width) of the robot in its own frame (m, along x and y); None
            takes them from the robot's collision box when it joins a simulation.
    """

    deceleration: float = 1.0
    protective_margin: float = 0.1
    warning_margin: float = 0.5
    side_margin: float = 0.05
    slow_factor: float = 0.5
    footprint: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        self.deceleration = _positive("deceleration", self.deceleration)
        self.protective_margin = _positive("protective_margin", self.protective_margin, True)
        self.warning_margin = _positive("warning_margin", self.warning_margin, True)
        self.side_margin = _positive("side_margin", self.side_margin, True)
        self.slow_factor = _positive("slow_factor", self.slow_factor)
        if self.slow_factor > 1.0:
            raise ValueError(
                f"SafetyFieldParams.slow_factor: expected a number in (0, 1], "
                f"got {self.slow_factor!r}"
            )
        if self.footprint is not None:
            fp = self.footprint
            if not (isinstance(fp, (list, tuple)) and len(fp) == 2):
                raise ValueError(
                    f"SafetyFieldParams.footprint: expected (length, width) in m, got {fp!r}"
                )
            self.footprint = (_positive("footprint", fp[0]), _positive("footprint", fp[1]))

    def protective_depth(self, speed: float) -> float:
        """Protective field depth ahead of the footprint at ``speed`` m/s (m)."""
        return speed * speed / (2.0 * self.deceleration) + self.protective_margin

    def warning_depth(self, speed: float) -> float:
        """Warning field depth ahead of the footprint at ``speed`` m/s (m)."""
        return self.protective_depth(speed) + self.warning_margin

    @classmethod
    def coerce(cls, value: Any, where: str) -> SafetyFieldParams | None:
        """``value`` as field parameters: None / False (off), True (defaults), a mapping or
        an instance.

        Raises:
            ValueError: for anything else, naming ``where`` and the value.
        """
        if value is None or value is False:
            return None
        if value is True:
            return cls()
        if isinstance(value, cls):
            return value
        if isinstance(value, dict):
            names = set(cls.__dataclass_fields__)
            unknown = sorted(set(value) - names)
            if unknown:
                raise ValueError(
                    f"{where}: unknown key {unknown[0]!r} (expected one of {sorted(names)})"
                )
            fp = value.get("footprint")
            return cls(**{**value, "footprint": tuple(fp) if isinstance(fp, list) else fp})
        raise ValueError(
            f"{where}: expected a mapping of safety field settings or true/false, got {value!r}"
        )
