"""What a fleet's master sends a vehicle, in no protocol's words: orders and instant tasks.

An :class:`Order` is a route of nodes joined by edges, each with a sequence number (nodes even,
edges odd, counting up along the route), some *released* (the base: the vehicle may drive
them) and the rest not yet (the horizon: the vehicle knows them but stops at the last released
node). A later order with the same ``order_id`` and a higher ``update`` extends the route: its
first node is the last released node of the one before (the stitching node). Nodes and edges
carry :class:`Task` s (pick, drop, charging ...), each with a blocking kind.

:class:`InstantTasks` are tasks to run at once, outside any order (cancel the order, pause,
report state ...). :class:`Rejection` is a message the transport could not read: it becomes an
error in the vehicle's state, as the master must be told.

Every command is plain data that round-trips through JSON (``to_json`` / ``command_from_json``),
so a trace can record it and a replay apply it again without any network.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from enum import Enum
from typing import Any

__all__ = [
    "Blocking",
    "Command",
    "Edge",
    "InstantTasks",
    "Node",
    "Order",
    "Rejection",
    "Task",
    "command_from_json",
]


class Blocking(str, Enum):
    """What a task lets happen while it runs."""

    NONE = "none"
    """Driving and other tasks go on."""
    SOFT = "soft"
    """Other tasks go on; the vehicle does not drive."""
    HARD = "hard"
    """Nothing else: the vehicle stands still and runs only this task."""


@dataclass(frozen=True)
class Task:
    """One thing to do: ``kind`` (``"pick"``, ``"drop"``, ``"start_charging"`` ...).

    Args:
        kind: What to do (the fleet interface's own names; a transport translates).
        task_id: Unique id the master tracks it by.
        blocking: What may happen while it runs.
        params: Its parameters (strings, numbers, booleans).
    """

    kind: str
    task_id: str
    blocking: Blocking = Blocking.HARD
    params: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Node:
    """A place on an order's route.

    Args:
        node_id: The master's name for the place (may repeat along a route).
        sequence: Even number, its place along the route.
        released: Part of the base (may be driven to) or of the horizon.
        x: World x (m), or None when the master gave no position.
        y: World y (m), or None.
        theta: Heading to have on arrival (rad), or None for any.
        deviation_xy: m within which the node counts as reached (None: the vehicle's own).
        deviation_theta: rad within which the heading counts as reached (None: any).
        map_id: The map the position is on, or None.
        tasks: What to do on arrival, in order.
    """

    node_id: str
    sequence: int
    released: bool = True
    x: float | None = None
    y: float | None = None
    theta: float | None = None
    deviation_xy: float | None = None
    deviation_theta: float | None = None
    map_id: str | None = None
    tasks: tuple[Task, ...] = ()

    @property
    def has_position(self) -> bool:
        """Whether the master said where the node is."""
        return self.x is not None and self.y is not None


@dataclass(frozen=True)
class Edge:
    """The way between two nodes of a route.

    Args:
        edge_id: The master's name for it.
        sequence: Odd number, between its two nodes'.
        released: Part of the base or of the horizon.
        start_node_id: Node it leaves from.
        end_node_id: Node it leads to.
        max_speed: Speed limit on it (m/s), or None.
        orientation: Heading to keep while driving it (rad), or None.
        orientation_global: ``orientation`` is in the world frame (else relative to the
            direction of travel).
        tasks: What to do when it is entered, in order.
    """

    edge_id: str
    sequence: int
    start_node_id: str
    end_node_id: str
    released: bool = True
    max_speed: float | None = None
    orientation: float | None = None
    orientation_global: bool = False
    tasks: tuple[Task, ...] = ()


@dataclass(frozen=True)
class Order:
    """A route to drive (nodes and edges in sequence order) under one order id.

    Args:
        order_id: The master's id; the same id with a higher ``update`` extends the route.
        update: Counts up with each update of the same order (0 for a new one).
        nodes: Nodes by ascending sequence.
        edges: Edges by ascending sequence.
    """

    order_id: str
    update: int
    nodes: tuple[Node, ...]
    edges: tuple[Edge, ...] = ()

    def to_json(self) -> dict[str, Any]:
        """Plain JSON data (``command_from_json`` reads it back)."""
        return {"type": "order", **asdict(self)}


@dataclass(frozen=True)
class InstantTasks:
    """Tasks to run at once, outside any order, in the order given."""

    tasks: tuple[Task, ...]

    def to_json(self) -> dict[str, Any]:
        """Plain JSON data (``command_from_json`` reads it back)."""
        return {"type": "instant", **asdict(self)}


@dataclass(frozen=True)
class Rejection:
    """A message the transport refused before it became a command.

    Args:
        kind: ``"validation"`` (not a valid message), ``"order"`` (an order that cannot be
            run) or ``"order_update"`` (an update that does not fit the order).
        description: What was wrong, for a person.
        references: ``(key, value)`` pairs naming what the error is about (order id, field).
    """

    kind: str
    description: str
    references: tuple[tuple[str, str], ...] = ()

    def to_json(self) -> dict[str, Any]:
        """Plain JSON data (``command_from_json`` reads it back)."""
        return {"type": "rejection", **asdict(self)}


Command = Order | InstantTasks | Rejection
"""Anything a master sends one vehicle."""


def _task(data: Mapping[str, Any]) -> Task:
    return Task(
        kind=data["kind"],
        task_id=data["task_id"],
        blocking=Blocking(data["blocking"]),
        params=dict(data.get("params", {})),
    )


def _tasks(items: Any) -> tuple[Task, ...]:
    return tuple(_task(t) for t in items)


def command_from_json(data: Mapping[str, Any]) -> Command:
    """The command that ``to_json`` wrote.

    Raises:
        ValueError: for data no ``to_json`` wrote (naming the ``type``).
    """
    kind = data.get("type")
    if kind == "order":
        nodes = tuple(Node(**{**n, "tasks": _tasks(n.get("tasks", ()))}) for n in data["nodes"])
        edges = tuple(Edge(**{**e, "tasks": _tasks(e.get("tasks", ()))}) for e in data["edges"])
        return Order(data["order_id"], int(data["update"]), nodes, edges)
    if kind == "instant":
        return InstantTasks(_tasks(data["tasks"]))
    if kind == "rejection":
        refs = tuple((str(k), str(v)) for k, v in data.get("references", ()))
        return Rejection(data["kind"], data["description"], refs)
    raise ValueError(f"fleet command: unknown type {kind!r} (expected order, instant, rejection)")
