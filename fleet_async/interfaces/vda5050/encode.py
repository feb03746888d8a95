"""Fleet interface snapshots -> VDA 5050 ``state``, ``visualization``, ``connection`` and
``factsheet`` messages (plain dicts; the transport adds the header and serialises).

Every message built here validates against the standard's schema of the configured version
(tests/interfaces check each kind).
"""

from __future__ import annotations

import math
import threading
from datetime import datetime, timezone
from typing import Any

from fleet_async.interfaces.snapshot import TaskStatus, VehicleSnapshot
from fleet_async.interfaces.vda5050.config import (
    ERROR_TYPES,
    Vda5050Config,
    to_vda_key,
    vda_action_type,
)

__all__ = ["Header", "connection", "state", "timestamp", "visualization"]

_STATUS = {
    TaskStatus.WAITING: "WAITING",
    TaskStatus.INITIALIZING: "INITIALIZING",
    TaskStatus.RUNNING: "RUNNING",
    TaskStatus.PAUSED: "PAUSED",
    TaskStatus.FINISHED: "FINISHED",
    TaskStatus.FAILED: "FAILED",
}


def timestamp(epoch: float, sim_time: float) -> str:
    """ISO 8601 UTC with milliseconds: ``epoch`` (Unix s) plus ``sim_time`` (s)."""
    moment = datetime.fromtimestamp(epoch + sim_time, tz=timezone.utc)
    return moment.isoformat(timespec="milliseconds").replace("+00:00", "Z")


class Header:
    """headerIds per topic and the fields every message of one vehicle starts with.

    Args:
        config: The vehicles' settings.
        serial: This vehicle's serialNumber.
        epoch: Unix time of sim time 0.
    """

    def __init__(self, config: Vda5050Config, serial: str, epoch: float) -> None:
        self.config = config
        self.serial = serial
        self.epoch = epoch
        self._ids: dict[str, int] = {}
        self._lock = threading.Lock()  # the simulation's and the network thread both stamp

    def make(self, topic: str, sim_time: float) -> dict[str, Any]:
        """The header of the next message on ``topic`` (its headerId counts up by one)."""
        with self._lock:
            header_id = self._ids.get(topic, -1) + 1
            self._ids[topic] = header_id
        return {
            "headerId": header_id,
            "timestamp": timestamp(self.epoch, sim_time),
            "version": self.config.version,
            "manufacturer": self.config.manufacturer,
            "serialNumber": self.serial,
        }


def _position(snap: Any, map_id: str) -> dict[str, Any]:
    return {
        "x": snap.x,
        "y": snap.y,
        "theta": math.remainder(snap.theta, 2 * math.pi),
        "mapId": map_id,
        "positionInitialized": True,
    }


def _velocity(snap: Any) -> dict[str, Any]:
    return {"vx": snap.vx, "vy": snap.vy, "omega": snap.omega}


def _node_states(snap: VehicleSnapshot, map_id: str, version: str) -> list[dict[str, Any]]:
    # 2.0's schema wants a theta in a node state's position, which a node may not have: the
    # position (optional) is given from 2.1 on.
    with_position = not version.startswith("2.0")
    return [
        {
            "nodeId": n,
            "sequenceId": seq,
            "released": rel,
            **({"nodePosition": {"x": x, "y": y, "mapId": map_id}} if with_position else {}),
        }
        for (n, seq, rel), (x, y) in zip(snap.nodes, snap.node_positions, strict=True)
    ]


def state(
    header: dict[str, Any], snap: VehicleSnapshot, map_id: str, version: str
) -> dict[str, Any]:
    """The ``state`` message of ``snap``."""
    charge: float = round(snap.battery_charge, 3)
    if version.startswith("2.0"):  # 2.0's schema has an integer batteryCharge
        charge = round(snap.battery_charge)
    return {
        **header,
        "orderId": snap.order_id,
        "orderUpdateId": snap.order_update,
        "lastNodeId": snap.last_node_id,
        "lastNodeSequenceId": snap.last_node_sequence,
        "driving": snap.driving,
        "paused": snap.paused,
        "distanceSinceLastNode": snap.distance_since_last_node,
        "operatingMode": "AUTOMATIC",
        "nodeStates": _node_states(snap, map_id, version),
        "edgeStates": [
            {"edgeId": e, "sequenceId": seq, "released": rel} for e, seq, rel in snap.edges
        ],
        "agvPosition": _position(snap, map_id),
        "velocity": _velocity(snap),
        "loads": [
            {"loadId": load.load_id, **({"weight": load.weight} if load.weight else {})}
            for load in snap.loads
        ],
        "actionStates": [
            {
                "actionId": t.task_id,
                "actionType": vda_action_type(t.kind),
                "actionStatus": _STATUS[t.status],
                **({"resultDescription": t.description} if t.description else {}),
            }
            for t in snap.tasks
        ],
        "batteryState": {"batteryCharge": charge, "charging": snap.charging},
        "errors": [
            {
                "errorType": ERROR_TYPES.get(e.kind, e.kind),
                "errorLevel": "FATAL" if e.fatal else "WARNING",
                "errorDescription": e.description,
                "errorReferences": [
                    {"referenceKey": to_vda_key(k), "referenceValue": v} for k, v in e.references
                ],
            }
            for e in snap.errors
        ],
        "information": [],
        "safetyState": {"eStop": "NONE", "fieldViolation": snap.field_violation},
    }


def visualization(header: dict[str, Any], snap: Any, map_id: str) -> dict[str, Any]:
    """The ``visualization`` message of ``snap`` (a VehiclePose or a VehicleSnapshot)."""
    return {**header, "agvPosition": _position(snap, map_id), "velocity": _velocity(snap)}


def connection(header: dict[str, Any], connection_state: str) -> dict[str, Any]:
    """A ``connection`` message: ``"ONLINE"``, ``"OFFLINE"`` or ``"CONNECTIONBROKEN"``."""
    return {**header, "connectionState": connection_state}
