"""Fleet interfaces: software in other processes drives the simulated fleet.

The transport-neutral part (this package's top level) serves robots as vehicles that take
orders and instant tasks and report snapshots of their state, at step boundaries; transports
translate a protocol onto it: :class:`InMemoryTransport` (same process),
``fleet_async.interfaces.vda5050`` (VDA 5050 over MQTT, the ``vda5050`` extra). See
docs/fleet-interfaces.md.
"""

from fleet_async.interfaces.commands import (
    Blocking,
    Command,
    Edge,
    InstantTasks,
    Node,
    Order,
    Rejection,
    Task,
    command_from_json,
)
from fleet_async.interfaces.fleet import FleetInterface, FleetListener, replay_commands
from fleet_async.interfaces.memory import InMemoryTransport
from fleet_async.interfaces.snapshot import (
    TaskProgress,
    TaskStatus,
    VehicleError,
    VehicleLoad,
    VehiclePose,
    VehicleSnapshot,
)
from fleet_async.interfaces.vehicle import INSTANT_TASKS, Vehicle

__all__ = [
    "INSTANT_TASKS",
    "Blocking",
    "Command",
    "Edge",
    "FleetInterface",
    "FleetListener",
    "InMemoryTransport",
    "InstantTasks",
    "Node",
    "Order",
    "Rejection",
    "Task",
    "TaskProgress",
    "TaskStatus",
    "Vehicle",
    "VehicleError",
    "VehicleLoad",
    "VehiclePose",
    "VehicleSnapshot",
    "command_from_json",
    "replay_commands",
]
