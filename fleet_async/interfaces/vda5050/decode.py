"""VDA 5050 ``order`` and ``instantActions`` payloads -> fleet interface commands.

Anything that is not a valid message of the protocol becomes a
:class:`~fleet_async.interfaces.commands.Rejection` of kind ``validation`` (reported to the
master as ``validationError``, with the headerId and topic as references); a valid message
asking for what a simulated vehicle cannot do (a NURBS trajectory, a corridor, another map)
becomes one of kind ``order`` (``orderError``). Nothing here raises on bad input.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

from fleet_async.interfaces.commands import (
    Blocking,
    Command,
    Edge,
    InstantTasks,
    Node,
    Order,
    Rejection,
    Task,
)
from fleet_async.interfaces.vda5050.config import (
    SUPPORTED_VERSIONS,
    Vda5050Config,
    from_vda_key,
    task_kind,
)
from fleet_async.interfaces.vda5050.schemas import validation_errors

__all__ = ["MAX_PAYLOAD_BYTES", "decode"]

MAX_PAYLOAD_BYTES = 4 * 1024 * 1024
"""Larger payloads are refused unread (validationError)."""

_UNSUPPORTED_EDGE_FIELDS = {
    "trajectory": "NURBS trajectories are not followed (edges are driven straight)",
    "corridor": "corridors are not supported (edges are driven on their line)",
}


def _refs(topic: str, data: Any) -> tuple[tuple[str, str], ...]:
    refs = [("topic", topic)]
    if isinstance(data, Mapping) and isinstance(data.get("headerId"), int):
        refs.insert(0, ("header_id", str(data["headerId"])))
    return tuple(refs)


def _invalid(topic: str, data: Any, problem: str) -> Rejection:
    return Rejection("validation", f"{topic}: {problem}", _refs(topic, data))


def _parse(topic: str, payload: bytes) -> Any:
    if len(payload) > MAX_PAYLOAD_BYTES:
        return _invalid(
            topic, None, f"payload of {len(payload)} bytes exceeds {MAX_PAYLOAD_BYTES} bytes"
        )
    try:
        return json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        return _invalid(topic, None, f"not JSON text ({type(exc).__name__}: {str(exc)[:120]})")


def _schema_version(data: Mapping[str, Any], config: Vda5050Config) -> str | None:
    """The schema to check ``data`` with: its own version's when shipped, if the major fits."""
    version = data.get("version")
    if not isinstance(version, str):
        return config.version
    if version.split(".")[0] != config.version.split(".")[0]:
        return None
    minor = ".".join(version.split(".")[:2])
    for supported in SUPPORTED_VERSIONS:
        if supported.startswith(minor + "."):
            return supported
    return config.version


def decode(topic: str, payload: bytes, config: Vda5050Config, serial: str) -> Command:
    """The command a payload on ``topic`` (``"order"`` or ``"instantActions"``) carries.

    Args:
        topic: The topic's last level.
        payload: The raw message.
        config: The vehicles' settings (version, manufacturer).
        serial: The vehicle's serialNumber (the topic's level).

    Returns:
        An Order, InstantTasks, or a Rejection saying what was wrong.
    """
    data = _parse(topic, payload)
    if isinstance(data, Rejection):
        return data
    if not isinstance(data, dict):
        return _invalid(topic, data, f"expected a JSON object, got {type(data).__name__}")
    version = _schema_version(data, config)
    if version is None:
        return _invalid(
            topic,
            data,
            f"version {data.get('version')!r} is not spoken here (this vehicle speaks "
            f"{config.version}, and 2.x messages of compatible minor versions)",
        )
    problems = validation_errors(version, topic, data)
    if problems:
        return _invalid(topic, data, "; ".join(problems))
    for key, expected in (("manufacturer", config.manufacturer), ("serialNumber", serial)):
        if data[key] != expected:
            return _invalid(topic, data, f"{key} {data[key]!r} is not this vehicle's {expected!r}")
    if topic == "order":
        return _order(data, config)
    return InstantTasks(tuple(_task(a) for a in data["actions"]))


def _task(action: Mapping[str, Any]) -> Task:
    params = {from_vda_key(str(p["key"])): p["value"] for p in action.get("actionParameters") or ()}
    return Task(
        kind=task_kind(action["actionType"]),
        task_id=action["actionId"],
        blocking=Blocking(action["blockingType"].lower()),
        params=params,
    )


def _node(data: Mapping[str, Any]) -> Node:
    pos = data.get("nodePosition") or {}
    deviation = pos.get("allowedDeviationXY", pos.get("allowedDeviationXy"))
    return Node(
        node_id=data["nodeId"],
        sequence=int(data["sequenceId"]),
        released=bool(data["released"]),
        x=_number(pos.get("x")),
        y=_number(pos.get("y")),
        theta=_number(pos.get("theta")),
        deviation_xy=_number(deviation),
        deviation_theta=_number(pos.get("allowedDeviationTheta")),
        map_id=pos.get("mapId"),
        tasks=tuple(_task(a) for a in data["actions"]),
    )


def _edge(data: Mapping[str, Any]) -> Edge:
    return Edge(
        edge_id=data["edgeId"],
        sequence=int(data["sequenceId"]),
        start_node_id=data["startNodeId"],
        end_node_id=data["endNodeId"],
        released=bool(data["released"]),
        max_speed=_number(data.get("maxSpeed")),
        orientation=_number(data.get("orientation")),
        orientation_global=str(data.get("orientationType", "TANGENTIAL")).upper() == "GLOBAL",
        tasks=tuple(_task(a) for a in data["actions"]),
    )


def _order(data: Mapping[str, Any], config: Vda5050Config) -> Command:
    order_refs = (("order_id", str(data["orderId"])), ("order_update", str(data["orderUpdateId"])))
    for edge in data["edges"]:
        for key, why in _UNSUPPORTED_EDGE_FIELDS.items():
            if edge.get(key) is not None:
                return Rejection(
                    "order",
                    f"order {data['orderId']!r}: edge {edge['edgeId']!r} has a {key}: {why}",
                    (*order_refs, ("edge_id", str(edge["edgeId"])), ("field", key)),
                )
    graph = config.route_graph
    named = []
    for node in data["nodes"]:
        if not node.get("nodePosition"):
            known = graph.nodes.get(str(node["nodeId"])) if graph is not None else None
            if known is None:
                where = "" if graph is None else " and the route graph has no such node"
                return Rejection(
                    "order",
                    f"order {data['orderId']!r}: node {node['nodeId']!r} has no nodePosition"
                    f"{where} (a simulated vehicle drives by coordinates)",
                    (*order_refs, ("node_id", str(node["nodeId"])), ("field", "nodePosition")),
                )
            node = {**node, "nodePosition": _graph_position(known)}
        named.append(node)
        map_id = node["nodePosition"].get("mapId")
        if config.map_id is not None and map_id != config.map_id:
            return Rejection(
                "order",
                f"order {data['orderId']!r}: node {node['nodeId']!r} is on map {map_id!r}; "
                f"this vehicle has map {config.map_id!r}",
                (*order_refs, ("node_id", str(node["nodeId"])), ("field", "mapId")),
            )
    nodes = sorted((_node(n) for n in named), key=lambda n: n.sequence)
    edges = sorted((_edge(e) for e in data["edges"]), key=lambda e: e.sequence)
    return Order(str(data["orderId"]), int(data["orderUpdateId"]), tuple(nodes), tuple(edges))


def _graph_position(node: Any) -> dict[str, Any]:
    """A nodePosition from a route graph's node (its map, its heading when it has one)."""
    pos: dict[str, Any] = {"x": node.x, "y": node.y, "mapId": node.map_id or ""}
    if node.theta is not None:
        pos["theta"] = node.theta
    return pos


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)
