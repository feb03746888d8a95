"""Ports, port values and the blackboard of a behaviour tree.

A node declares its ports; in the XML each port is an attribute whose value is either a literal
(``seconds="2.5"``, ``goal="1;2;0.1"``) or a blackboard reference (``goal="{goal}"``, and
``{=}`` for "the entry with the port's own name"), as in BehaviorTree.CPP. Literals are converted
when the tree is loaded, so a bad literal is a load error with its line; blackboard values are
used as they are (a string is converted like a literal).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from enum import Enum
from typing import Any

from fleet_async.core import Pose

__all__ = [
    "REQUIRED",
    "Blackboard",
    "InputPort",
    "NodeStatus",
    "OutputPort",
    "Port",
    "blackboard_key",
    "convert_literal",
]

REQUIRED: Any = object()
"""Default of a port that must be given."""


class NodeStatus(str, Enum):
    """What a node returns. RUNNING is never returned here: a node that runs is a mission
    parked on an await (see docs/behavior-trees.md)."""

    SUCCESS = "SUCCESS"
    FAILURE = "FAILURE"
    RUNNING = "RUNNING"


@dataclass(frozen=True)
class Port:
    """One port of a node model.

    Attributes:
        name: Attribute name in the XML.
        direction: "input" or "output".
        kind: How a literal is read: ``str``, ``int``, ``float``, ``bool``, ``"pose"``
            (``x;y;z`` or ``x;y;z;yaw``), ``"path"`` (poses separated by ``|``), ``"object"``
            (a sim object's name or a blackboard object), ``"any"``, or a callable
            ``str -> value``.
        default: Value when the attribute is absent (``REQUIRED``: it must be given). For an
            output port, the blackboard key written when the attribute is absent (or None).
        description: For documentation.
    """

    name: str
    direction: str = "input"
    kind: Any = str
    default: Any = REQUIRED
    description: str = ""


def InputPort(  # BehaviorTree.CPP's spelling
    name: str, kind: Any = str, default: Any = REQUIRED, description: str = ""
) -> Port:
    """An input port (``kind``: see :class:`Port`)."""
    return Port(name, "input", kind, default, description)


def OutputPort(  # BehaviorTree.CPP's spelling
    name: str, default_key: str | None = None, description: str = ""
) -> Port:
    """An output port; without an attribute it writes ``default_key`` (or nothing)."""
    return Port(name, "output", "any", default_key, description)


def blackboard_key(value: str, port: str) -> str | None:
    """The key of a ``{key}`` reference (``{=}`` means ``port``), or None for a literal.

    Raises:
        ValueError: for a malformed reference such as ``{goal``.
    """
    text = value.strip()
    if text.startswith("{") and text.endswith("}"):
        key = text[1:-1].strip()
        if key == "=":
            return port
        if not key or "{" in key or "}" in key:
            raise ValueError(f"malformed blackboard reference {value!r}")
        return key
    if "{" in text or "}" in text:
        raise ValueError(f"malformed blackboard reference {value!r} (expected '{{key}}')")
    return None


def _numbers(text: str, what: str) -> list[float]:
    parts = [p for p in text.replace(",", ";").split(";") if p.strip()]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"expected {what}, got {text!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"expected finite numbers, got {text!r}")
    return values


def _pose(value: Any) -> Pose:
    if isinstance(value, Pose):
        return value
    if isinstance(value, str):
        values = _numbers(value, "'x;y;z' or 'x;y;z;yaw'")
    else:
        values = [float(v) for v in value]
    if len(values) == 3:
        return Pose(values)
    if len(values) == 4:
        return Pose.from_euler(values[0], values[1], values[2], yaw=values[3])
    raise ValueError(f"expected 'x;y;z' or 'x;y;z;yaw', got {value!r}")


def _path(value: Any) -> list[Pose]:
    if isinstance(value, Pose):
        return [value]
    if isinstance(value, str):
        return [_pose(part) for part in value.split("|") if part.strip()] or _path_error(value)
    items = list(value)
    if items and all(isinstance(v, (int, float)) for v in items):
        return [_pose(items)]
    return [_pose(item) for item in items] or _path_error(value)


def _path_error(value: Any) -> list[Pose]:
    raise ValueError(f"expected poses 'x;y;z | x;y;z | ...', got {value!r}")


def _bool(value: Any) -> bool:
    if isinstance(value, bool):
        return value
    text = str(value).strip().lower()
    if text in ("true", "1", "yes"):
        return True
    if text in ("false", "0", "no"):
        return False
    raise ValueError(f"expected true or false, got {value!r}")


def _int(value: Any) -> int:
    if isinstance(value, bool):
        raise ValueError(f"expected an integer, got {value!r}")
    if isinstance(value, int):
        return value
    try:
        return int(str(value).strip())
    except ValueError:
        raise ValueError(f"expected an integer, got {value!r}") from None


def _float(value: Any) -> float:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    try:
        number = float(str(value).strip())
    except ValueError:
        raise ValueError(f"expected a number, got {value!r}") from None
    if not math.isfinite(number):
        raise ValueError(f"expected a finite number, got {value!r}")
    return number


_CONVERTERS: dict[Any, Callable[[Any], Any]] = {
    str: str,
    int: _int,
    float: _float,
    bool: _bool,
    "pose": _pose,
    "path": _path,
    "any": lambda v: v,
    "object": lambda v: v,  # names are resolved against the simulation when the node runs
}


def convert_literal(kind: Any, value: Any) -> Any:
    """``value`` (a literal string, or a blackboard value) as a port of ``kind`` wants it.

    Raises:
        ValueError: describing what was expected.
    """
    converter = _CONVERTERS.get(kind)
    if converter is None:
        if not callable(kind):
            raise TypeError(f"port kind {kind!r} is neither a known kind nor callable")
        converter = kind
    if kind in (int, float, bool, "pose", "path") or isinstance(value, str):
        return converter(value)
    return value


class Blackboard:
    """Key/value entries shared by the nodes of a tree; a SubTree gets a child blackboard.

    Args:
        values: Initial entries.
        parent: The blackboard of the tree that holds the SubTree.
        remap: This blackboard's key -> the parent's key (``port="{parent_key}"``).
        autoremap: Keys not found here are read from (and written to) the parent under the
            same name (``_autoremap="true"``).
    """

    def __init__(
        self,
        values: Mapping[str, Any] | None = None,
        parent: Blackboard | None = None,
        remap: Mapping[str, str] | None = None,
        autoremap: bool = False,
    ) -> None:
        self._values: dict[str, Any] = dict(values or {})
        self._parent = parent
        self._remap = dict(remap or {})
        self._autoremap = autoremap

    def _route(self, key: str) -> tuple[Blackboard, str] | None:
        if self._parent is not None:
            if key in self._remap:
                return self._parent, self._remap[key]
            if self._autoremap and key not in self._values:
                return self._parent, key
        return None

    def __getitem__(self, key: str) -> Any:
        route = self._route(key)
        if route is not None:
            return route[0][route[1]]
        return self._values[key]

    def __setitem__(self, key: str, value: Any) -> None:
        route = self._route(key)
        if route is not None:
            route[0][route[1]] = value
        else:
            self._values[key] = value

    def __contains__(self, key: object) -> bool:
        if not isinstance(key, str):
            return False
        route = self._route(key)
        return key in self._values if route is None else route[1] in route[0]

    def get(self, key: str, default: Any = None) -> Any:
        """The entry ``key``, or ``default``."""
        try:
            return self[key]
        except KeyError:
            return default

    def __iter__(self) -> Iterator[str]:
        return iter(self.as_dict())

    def as_dict(self) -> dict[str, Any]:
        """This blackboard's own entries (a copy)."""
        return dict(self._values)

    def __repr__(self) -> str:
        return f"Blackboard({self._values!r})"
