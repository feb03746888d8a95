"""The in-memory transport: a master in the same process, no broker, no network.

Useful for tests of a dispatcher written in Python and as the smallest example of a transport:
it hands commands to :meth:`FleetInterface.submit` and keeps what the vehicles report.
"""

from __future__ import annotations

from collections import defaultdict

from fleet_async.interfaces.commands import Command
from fleet_async.interfaces.fleet import FleetInterface
from fleet_async.interfaces.snapshot import VehiclePose, VehicleSnapshot

__all__ = ["InMemoryTransport"]


class InMemoryTransport:
    """Talks to a :class:`FleetInterface` from the same process.

    Args:
        fleet: The served fleet.
        keep: How many states to keep per vehicle (the oldest go first).

    Attributes:
        states: Per vehicle, ``(snapshot, reasons)`` of every state reported, oldest first.
        visualizations: Per vehicle, the number of visualization snapshots reported.
        factsheet_requests: Vehicles whose factsheet was asked for, in order.
    """

    def __init__(self, fleet: FleetInterface, keep: int = 10_000) -> None:
        self.fleet = fleet
        self._keep = int(keep)
        self.states: dict[str, list[tuple[VehicleSnapshot, tuple[str, ...]]]] = defaultdict(list)
        self.visualizations: dict[str, int] = defaultdict(int)
        self.factsheet_requests: list[str] = []
        fleet.add_listener(self)

    def send(self, vehicle: str, command: Command) -> None:
        """Send ``command`` to ``vehicle`` (applied at the next step boundary)."""
        self.fleet.submit(vehicle, command)

    def latest(self, vehicle: str) -> VehicleSnapshot | None:
        """The last state ``vehicle`` reported, or None."""
        log = self.states.get(vehicle)
        return log[-1][0] if log else None

    def close(self) -> None:
        """Stop listening."""
        self.fleet.remove_listener(self)

    # ----- FleetListener ----------------------------------------------------------------------

    def on_state(self, snapshot: VehicleSnapshot, reasons: tuple[str, ...]) -> None:
        """Keep the state."""
        log = self.states[snapshot.name]
        log.append((snapshot, reasons))
        if len(log) > self._keep:
            del log[0]

    def on_visualization(self, pose: VehiclePose) -> None:
        """Count it."""
        self.visualizations[pose.name] += 1

    def on_factsheet_request(self, vehicle: str) -> None:
        """Note it."""
        self.factsheet_requests.append(vehicle)
