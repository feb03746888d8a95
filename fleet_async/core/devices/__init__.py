"""Devices of a building: doors, elevators and workcells (dispensers, ingestors).

Each device is an Agent subclass with its own spawn params (``Door`` / ``DoorParams``,
``Elevator`` / ``ElevatorParams``, ``Workcell`` / ``WorkcellParams``), registered as the
scenario entity types ``door``, ``elevator`` and ``workcell``; ``WorkcellPlugin`` declares
stations from a scenario's ``plugins`` section. Their bodies move through the device motion
system (``motion.py``), so they behave the same with or without missions; their commands are
actions on their own queues, which missions await through ``agent.submit``. Open-RMF doors and
lifts in Gazebo worlds become devices when the world is loaded (``rmf_world.py``). See
docs/devices.md.

May import ``managers`` and below at run time.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from fleet_async.core.base.device_events import DeviceEvents
from fleet_async.core.devices.device import Device
from fleet_async.core.devices.door import Door, DoorAction, DoorParams, DoorType
from fleet_async.core.devices.elevator import Elevator, ElevatorTrip
from fleet_async.core.devices.elevator_params import (
    ElevatorParams,
    ElevatorRequestPolicy,
    ElevatorRequestResult,
    ElevatorState,
)
from fleet_async.core.devices.motion import DeviceAction, DeviceMotion
from fleet_async.core.devices.workcell import (
    DispenseAction,
    IngestAction,
    Workcell,
    WorkcellKind,
    WorkcellParams,
)
from fleet_async.core.devices.workcell_plugin import WorkcellPlugin
from fleet_async.core.managers.sim_object_manager import register_entity_class

if TYPE_CHECKING:
    from fleet_async.core.missions.host import MissionDoor, MissionElevator

__all__ = [
    "Device",
    "DeviceAction",
    "DeviceEvents",
    "DeviceMotion",
    "DispenseAction",
    "Door",
    "DoorAction",
    "DoorParams",
    "DoorType",
    "Elevator",
    "ElevatorParams",
    "ElevatorRequestPolicy",
    "ElevatorRequestResult",
    "ElevatorState",
    "ElevatorTrip",
    "IngestAction",
    "Workcell",
    "WorkcellKind",
    "WorkcellParams",
    "WorkcellPlugin",
]

for _cls in (Door, Elevator, Workcell):
    register_entity_class(_cls.device_type, _cls)

if TYPE_CHECKING:
    # The mission layer names a door and a lift by the seam's protocols (``tasks/devices.py``):
    # the type checker holds the classes to them here, where both are in view.
    _door_for_missions: type[MissionDoor] = Door
    _lift_for_missions: type[MissionElevator] = Elevator
