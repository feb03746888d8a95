"""Settings of served VDA 5050 vehicles, and the standard's names for the fleet interface's.

The fleet interface speaks its own words (``pick``, ``start_charging``, ``order_update``);
this module is the dictionary between them and VDA 5050's (``pick``, ``startCharging``,
``orderUpdateError``). A name without an entry passes unchanged, so a refusal can quote the
master's own word back.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

__all__ = [
    "SUPPORTED_VERSIONS",
    "Vda5050Config",
    "from_vda_key",
    "task_kind",
    "to_vda_key",
    "vda_action_type",
]

SUPPORTED_VERSIONS = ("2.0.0", "2.1.0")
"""Protocol versions whose schemas ship with the package."""

_ACTIONS = {
    "pick": "pick",
    "drop": "drop",
    "startCharging": "start_charging",
    "stopCharging": "stop_charging",
    "cancelOrder": "cancel_order",
    "startPause": "start_pause",
    "stopPause": "stop_pause",
    "stateRequest": "state_request",
    "factsheetRequest": "factsheet_request",
    "initPosition": "init_position",
}
_ACTION_NAMES = {kind: vda for vda, kind in _ACTIONS.items()}

ERROR_TYPES = {
    "validation": "validationError",
    "order": "orderError",
    "order_update": "orderUpdateError",
    "no_order_to_cancel": "noOrderToCancel",
    "task_failed": "actionError",
}
"""The fleet interface's error kinds -> VDA 5050 errorType."""

_KEYS = {
    "order_id": "orderId",
    "order_update": "orderUpdateId",
    "node_id": "nodeId",
    "edge_id": "edgeId",
    "task_id": "actionId",
    "task_kind": "actionType",
    "header_id": "headerId",
    "topic": "topic",
    "field": "field",
}


def task_kind(action_type: str) -> str:
    """The fleet interface's task kind for a VDA 5050 actionType (unknown ones unchanged)."""
    return _ACTIONS.get(action_type, action_type)


def vda_action_type(kind: str) -> str:
    """The VDA 5050 actionType for a task kind (unknown ones unchanged)."""
    return _ACTION_NAMES.get(kind, kind)


def to_vda_key(key: str) -> str:
    """An errorReference key for a fleet interface reference key."""
    return _KEYS.get(key, key)


def from_vda_key(key: str) -> str:
    """``loadId`` -> ``load_id``: an action parameter's key in the fleet interface's style."""
    return re.sub(r"(?<=[a-z0-9])([A-Z])", lambda m: "_" + m.group(1).lower(), key)


@dataclass(frozen=True)
class Vda5050Config:
    """How served robots appear as VDA 5050 vehicles.

    Topics are ``interface_name/v<major>/manufacturer/serial_number/<topic>``.

    Args:
        version: Protocol version spoken (``"2.1.0"``; ``"2.0.0"`` for 2.0 masters).
        interface_name: First topic level.
        manufacturer: Topic level and header field of every vehicle.
        serial_numbers: ``{robot name: serialNumber}``; robots not listed use their name,
            made unique (``name``, ``name_2`` ...) and without ``/``, ``+``, ``#`` or ``$``.
        state_period: s between states when nothing happens (<= 30).
        visualization_period: s between visualization messages (0: none).
        epoch: Wall-clock time (Unix s) that sim time 0 maps to in timestamps; None: when
            serving starts.
        series_name: The factsheet's seriesName (default: the robot's model or name).
        map_id: The vehicles' map: an order on another mapId is refused (orderError); None
            takes any mapId and reports the one of the last order's nodes ("map" before any).
        route_graph: A ``RouteGraph`` whose node ids orders may name without a nodePosition
            (the node's position, heading and map are taken from the graph); None: the served
            simulation's ``route_graph`` when it has one.

    Raises:
        ValueError: naming the field and the value.
    """

    version: str = "2.1.0"
    interface_name: str = "uagv"
    manufacturer: str = "fleet_async"
    serial_numbers: dict[str, str] = field(default_factory=dict)
    state_period: float = 30.0
    visualization_period: float = 0.1
    epoch: float | None = None
    series_name: str | None = None
    map_id: str | None = None
    route_graph: Any = None

    def __post_init__(self) -> None:
        if self.version not in SUPPORTED_VERSIONS:
            raise ValueError(
                f"Vda5050Config.version: expected one of {list(SUPPORTED_VERSIONS)}, "
                f"got {self.version!r}"
            )
        for name in ("interface_name", "manufacturer"):
            value = getattr(self, name)
            if not isinstance(value, str) or not value or _BAD_LEVEL.search(value):
                raise ValueError(
                    f"Vda5050Config.{name}: expected a non-empty topic level without / + # $, "
                    f"got {value!r}"
                )
        for robot, serial in self.serial_numbers.items():
            if not isinstance(serial, str) or not serial or _BAD_LEVEL.search(serial):
                raise ValueError(
                    f"Vda5050Config.serial_numbers[{robot!r}]: expected a non-empty topic level "
                    f"without / + # $, got {serial!r}"
                )
        if not 0 < self.state_period <= 30:
            raise ValueError(
                f"Vda5050Config.state_period: expected a number in (0, 30] s, "
                f"got {self.state_period!r}"
            )
        if not self.visualization_period >= 0:
            raise ValueError(
                "Vda5050Config.visualization_period: expected a number >= 0 s, "
                f"got {self.visualization_period!r}"
            )

    @property
    def major(self) -> str:
        """The topic's version level: ``"v2"``."""
        return "v" + self.version.split(".")[0]

    def topic(self, serial: str, name: str) -> str:
        """The full topic of ``name`` (``"order"`` ...) for vehicle ``serial``."""
        return f"{self.interface_name}/{self.major}/{self.manufacturer}/{serial}/{name}"

    def assign_serials(self, robots: list[str]) -> dict[str, str]:
        """``{robot: serialNumber}``: listed ones as given, the others their name, unique."""
        taken: set[str] = set(self.serial_numbers.values())
        out: dict[str, str] = {}
        for robot in robots:
            if robot in self.serial_numbers:
                out[robot] = self.serial_numbers[robot]
                continue
            base = _BAD_LEVEL.sub("_", robot) or "vehicle"
            serial, n = base, 1
            while serial in taken:
                n += 1
                serial = f"{base}_{n}"
            taken.add(serial)
            out[robot] = serial
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any], where: str = "serve") -> Vda5050Config:
        """Build from a scenario's ``serve`` section keys (unknown keys are errors).

        Raises:
            ValueError: naming ``where``, the key and the value.
        """
        names = set(cls.__dataclass_fields__) - {"route_graph"}  # the scenario's own graph
        unknown = sorted(set(data) - names)
        if unknown:
            raise ValueError(f"{where}: unknown key(s) {unknown}; valid: {sorted(names)}")
        try:
            return cls(**data)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{where}: {exc}") from None


_BAD_LEVEL = re.compile(r"[/+#$\s]")
