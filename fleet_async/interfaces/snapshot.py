"""What a vehicle tells its master, in no protocol's words: a snapshot of its state.

A snapshot is taken at a step boundary and is immutable: a transport may hand it to another
thread (the network side) while the simulation steps on.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple

__all__ = [
    "TaskProgress",
    "TaskStatus",
    "VehicleError",
    "VehicleLoad",
    "VehiclePose",
    "VehicleSnapshot",
]


class TaskStatus(str, Enum):
    """Where a task of an order (or an instant task) stands."""

    WAITING = "waiting"
    INITIALIZING = "initializing"
    RUNNING = "running"
    PAUSED = "paused"
    FINISHED = "finished"
    FAILED = "failed"


@dataclass(frozen=True)
class TaskProgress:
    """One task's state.

    Args:
        task_id: The master's id of it.
        kind: Its kind (``"pick"`` ...).
        status: Where it stands.
        description: Why it failed, or what it produced, or "".
    """

    task_id: str
    kind: str
    status: TaskStatus
    description: str = ""


@dataclass(frozen=True)
class VehicleError:
    """An error the vehicle reports until it is resolved.

    Args:
        kind: ``"validation"``, ``"order"``, ``"order_update"``, ``"no_order_to_cancel"`` or
            ``"task_failed"``.
        description: For a person.
        fatal: The vehicle cannot go on without help (else a warning).
        references: ``(key, value)`` pairs: what the error is about.
    """

    kind: str
    description: str
    fatal: bool = False
    references: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class VehicleLoad:
    """Something the vehicle carries (an attached object).

    Args:
        load_id: The object's name (its id when it has none).
        weight: kg, or None when not known.
    """

    load_id: str
    weight: float | None = None


@dataclass(frozen=True)
class VehicleSnapshot:
    """A vehicle's state at one step boundary.

    Args:
        name: The vehicle (the robot's name).
        step: Step count when taken; ``sim_time`` is ``step * timestep``.
        sim_time: s.
        x: Position in the world frame (m).
        y: Position in the world frame (m).
        theta: Heading in the world frame (rad).
        vx: Velocity along the vehicle's heading (m/s).
        vy: Velocity to the vehicle's left (m/s).
        omega: Yaw rate (rad/s).
        driving: Whether it is moving.
        paused: Whether it was paused by its master.
        battery_charge: State of charge in percent (100 without a battery).
        charging: Whether it is charging.
        order_id: The current (or last) order's id, "" before any.
        order_update: That order's update number.
        last_node_id: The last node reached, "" before any.
        last_node_sequence: Its sequence number (0 before any).
        nodes: ``(node_id, sequence, released)`` of nodes still to reach.
        edges: ``(edge_id, sequence, released)`` of edges still to drive.
        tasks: The state of every task of the current order and of recent instant tasks.
        loads: What it carries.
        errors: Errors not yet resolved.
        distance_since_last_node: m driven since the last node.
        node_positions: ``(x, y)`` (m) of each of ``nodes``, in the same order.
        field_violation: Whether something is in its protective safety field (it is stopped
            by it; VDA 5050's ``safetyState.fieldViolation``).
    """

    name: str
    step: int
    sim_time: float
    x: float
    y: float
    theta: float
    vx: float
    vy: float
    omega: float
    driving: bool
    paused: bool
    battery_charge: float
    charging: bool
    order_id: str
    order_update: int
    last_node_id: str
    last_node_sequence: int
    nodes: tuple[tuple[str, int, bool], ...]
    edges: tuple[tuple[str, int, bool], ...]
    tasks: tuple[TaskProgress, ...]
    loads: tuple[VehicleLoad, ...]
    errors: tuple[VehicleError, ...]
    distance_since_last_node: float = 0.0
    node_positions: tuple[tuple[float, float], ...] = ()
    field_violation: bool = False


class VehiclePose(NamedTuple):
    """Where a vehicle is and how it moves: what a visualization message says.

    Read for the whole served fleet at once from the state store (``FleetInterface``).
    """

    name: str
    step: int
    sim_time: float
    x: float
    y: float
    theta: float
    vx: float
    vy: float
    omega: float
