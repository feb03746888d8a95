"""Names of the events that devices (doors, elevators, workcells) emit on the simulation bus.

Kept apart from :class:`~fleet_async.core.base.events.SimEvents` (the reference API's own list)
so that the device list can grow without touching it. Every event is emitted on ``sim.events``
and, when someone asked for it, on the device's own bus (``device.events``); missions wait for
one with ``await sim.events.wait(DeviceEvents.DOOR_STATE_CHANGED, where=...)``.
"""

from __future__ import annotations

__all__ = ["DeviceEvents"]


class DeviceEvents:
    """Device event names, with the payload keys each carries."""

    DOOR_STATE_CHANGED = "door_state_changed"
    """A door's DoorState changed; payload ``door``, ``state``, ``previous``."""
    ELEVATOR_STATE_CHANGED = "elevator_state_changed"
    """An elevator's ElevatorState changed; payload ``elevator``, ``state``, ``previous``,
    ``floor`` (the current floor; the departure floor while moving), ``target_floor``."""
    ELEVATOR_DEPARTED = "elevator_departed"
    """A trip began; payload ``elevator``, ``floor`` (departure), ``target_floor``,
    ``passengers`` (the objects it carries, a tuple)."""
    ELEVATOR_ARRIVED = "elevator_arrived"
    """A trip ended at its floor; payload ``elevator``, ``floor``, ``passengers`` (released)."""
    ELEVATOR_RIDE_ABANDONED = "elevator_ride_abandoned"
    """A mission riding a lift stopped mid-ride; the lift finishes its trip and the robot stays
    on the platform; payload ``elevator``, ``robot``, ``floor`` (where the lift will stop)."""
    WORKCELL_DISPENSED = "workcell_dispensed"
    """A dispenser handed an item to a robot; payload ``workcell``, ``robot``, ``item``."""
    WORKCELL_INGESTED = "workcell_ingested"
    """An ingestor consumed an item; payload ``workcell``, ``robot``, ``item``."""

    @classmethod
    def all(cls) -> tuple[str, ...]:
        """Every device event name, in declaration order."""
        return tuple(v for k, v in vars(cls).items() if k.isupper() and isinstance(v, str))
