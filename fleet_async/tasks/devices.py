"""Device missions: a lift and a doorway shared between missions, riding, passing through.

A device's own commands (``door.open()``, ``elevator.go_to(floor)``, ``station.dispense(robot)``)
are actions on its queue that missions await. What takes several steps with the mission
layer's primitives lives here:

- :func:`device_resource`: the sim-aware :class:`~fleet_async.tasks.resources.Resource`
  (capacity 1) through which missions share a door's doorway or a lift, under the Resource
  rules (by priority, then request order).
- :func:`ride` (``await elevator.ride(robot, floor)``): hold the lift, call it to the robot's
  floor, board, travel, alight. A mission stopped (cancelled, interrupted) while the lift
  travels does not stop the lift: it finishes its trip and the robot stays on the platform;
  a warning and a ``DeviceEvents.ELEVATOR_RIDE_ABANDONED`` event name the robot and the floor.
- :func:`pass_through` (``await door.pass_through(robot, path)``): hold the doorway, open the
  door, drive through, and close it behind when nobody waits for the doorway.

Importing this module registers ``ride`` and ``pass_through`` as the missions behind the
devices' methods of those names. ``fleet_async.tasks`` imports it, so they are registered once
the mission layer is loaded (``fleet_async.run``, ``import fleet_async.tasks``, or the first
public name taken from ``fleet_async``; a bare ``import fleet_async`` binds its names lazily
and loads nothing).
"""

from __future__ import annotations

import logging
import weakref
from typing import TYPE_CHECKING, Any

from fleet_async.core.missions import ActionStatus, DeviceEvents, register_mission_hook
from fleet_async.tasks.resources import Resource
from fleet_async.tasks.waits import action_error

if TYPE_CHECKING:
    from fleet_async.core.missions import MissionDevice, MissionDoor, MissionElevator

__all__ = ["device_resource", "pass_through", "ride"]

logger = logging.getLogger(__name__)

_RESOURCES: weakref.WeakKeyDictionary[Any, Resource] = weakref.WeakKeyDictionary()
_CLOSING: weakref.WeakKeyDictionary[Any, Any] = weakref.WeakKeyDictionary()


def device_resource(device: MissionDevice) -> Resource:
    """The Resource (capacity 1) missions share ``device`` through: a lift's cabin, a door's
    doorway. Created on first use; the same object for the device's lifetime.

    Raises:
        ValueError: if ``device`` is not part of a simulation.
    """
    resource = _RESOURCES.get(device)
    if resource is None:
        sim = device.sim_core
        if sim is None:
            raise ValueError(f"device_resource: {device!r} is not part of a simulation")
        resource = _RESOURCES[device] = Resource(sim, capacity=1)
    return resource


async def ride(
    elevator: MissionElevator,
    robot: Any,
    floor: str,
    *,
    exit_pose: Any = None,
    priority: float = 0,
) -> Any:
    """Take ``robot`` to ``floor`` with ``elevator``: wait for the lift (its Resource), call it
    to the robot's floor, drive onto the platform's centre, travel, drive off.

    Args:
        elevator: The lift.
        robot: An agent standing on one of the lift's floors (its base at or above it).
        floor: Destination floor.
        exit_pose: Where the robot drives to at ``floor`` (default: the floor's landing, at
            the robot's height above the floor).
        priority: Resource priority of the ride (lower first).

    Returns:
        The finished move that took the robot off the lift (None if it already was at
        ``floor``).

    Raises:
        ValueError: for an unknown floor.
        ActionFailedError / ActionCancelledError: if a move or the trip failed or was
            cancelled from outside.
    """
    sim = elevator.sim_core
    if sim is None:
        raise ValueError(f"ride: {elevator!r} is not part of a simulation")
    elevator.floor_height(floor)  # an unknown floor fails before anything waits
    async with device_resource(elevator).request(priority=priority):
        here = robot.get_pose()
        start = elevator.floor_at(here.z)
        if start == floor:
            return None
        lift_z = here.z - elevator.floor_height(start)
        if elevator.is_moving or elevator.pending_floors or not elevator.is_at(start):
            await elevator.go_to(start)  # call it
        aboard = elevator.platform_pose(start, lift_z)
        aboard.orientation = here.orientation.copy()
        await robot.move(aboard)
        trip = elevator.queue_trip(floor)
        try:
            await sim.wait_until(trip.is_complete)
        except BaseException:
            if not trip.is_complete():
                _abandoned(elevator, robot, floor)
            raise
        if trip.status is not ActionStatus.COMPLETED:
            error = action_error(trip)
            assert error is not None
            raise error
        goal = exit_pose if exit_pose is not None else elevator.landing_pose(floor, lift_z)
        return await robot.move(goal)


def _abandoned(elevator: MissionElevator, robot: Any, floor: str) -> None:
    name = robot.name or repr(robot)
    logger.warning(
        "a mission stopped while %s rode %s: the lift finishes its trip to %r and %s stays on "
        "the platform",
        name,
        elevator.name or repr(elevator),
        floor,
        name,
    )
    sim = elevator.sim_core
    if sim is not None:
        sim.events.emit(
            DeviceEvents.ELEVATOR_RIDE_ABANDONED, elevator=elevator, robot=robot, floor=floor
        )


async def pass_through(
    door: MissionDoor,
    robot: Any,
    path: Any,
    *,
    close_after: bool = True,
    priority: float = 0,
) -> Any:
    """Take ``robot`` through ``door``: wait for the doorway (its Resource), open the door
    (reversing a close that the previous robot left running), drive ``path``, and, if
    ``close_after`` and nobody waits for the doorway, start closing the door (not awaited: the
    robot goes on while it closes).

    Args:
        door: The door.
        robot: The agent.
        path: Where to drive (a Pose, a list of Poses or a Path), through the doorway.
        close_after: Close behind when the doorway is free.
        priority: Resource priority (lower first).

    Returns:
        The finished move.

    Raises:
        ActionFailedError / ActionCancelledError: if the door or the move failed.
    """
    doorway = device_resource(door)
    async with doorway.request(priority=priority):
        closing = _CLOSING.pop(door, None)
        if closing is not None and not closing.done:
            closing.cancel()  # a door controller reverses a closing door for the next robot
        await door.open()
        moved = await robot.move(path)
        if close_after and not doorway.queue:
            _CLOSING[door] = door.close(detached=True)  # outlives this mission
        return moved


register_mission_hook("elevator.ride", ride)
register_mission_hook("door.pass_through", pass_through)
