"""Route graphs from files: a simple YAML graph, LIF (VDMA's Layout Interchange Format) and
Open-RMF nav graphs (a YAML file with ``levels``: ``routes/rmf.py``).

YAML graph (every key checked; an unknown one is an error naming it and the file)::

    default_speed: 1.0            # m/s for edges without max_speed (shortest paths); optional
    map_id: hall1                 # optional, for every node
    nodes:
      - {id: A, x: 0.0, y: 0.0}
      - {id: B, x: 5.0, y: 0.0, theta: 0.0}
    edges:
      - {id: AB, from: A, to: B, max_speed: 1.5, bidirectional: true}   # also BA: "AB~"

A bidirectional edge ``id`` adds its reverse as ``id~`` (or ``reverse_id``, when given).

LIF (JSON, ``metaInformation`` and ``layouts``): each layout's ``nodes`` (``nodeId``,
``nodePosition`` ``x`` / ``y``, the heading ``theta`` of its vehicle-type properties) and
``edges`` (``edgeId``, ``startNodeId``, ``endNodeId``, the ``maxSpeed`` of its vehicle-type
properties). ``layout_id`` picks a layout when there are several; ``vehicle_type`` picks the
vehicle type whose properties apply (default: the first listed on each node and edge). Nodes
get the layout's ``layoutLevelId`` as their ``map_id``. Stations and actions are not read.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fleet_async.core.base.config_utils import load_yaml_config
from fleet_async.core.routes.graph import RouteGraph, RouteNode
from fleet_async.core.routes.rmf import route_graph_from_rmf

__all__ = ["load_route_graph", "route_graph_from_lif", "route_graph_from_mapping"]

_TOP = {"default_speed", "map_id", "nodes", "edges"}
_NODE = {"id", "x", "y", "theta", "map_id"}
_EDGE = {"id", "from", "to", "max_speed", "bidirectional", "reverse_id"}


def load_route_graph(
    source: str | os.PathLike[str] | Mapping[str, Any],
    *,
    layout_id: str | None = None,
    vehicle_type: str | None = None,
) -> RouteGraph:
    """A route graph from a YAML graph, an Open-RMF nav graph (YAML with ``levels``) or a LIF
    file (``.json`` / ``.lif``), or a mapping of one of them.

    Raises:
        FileNotFoundError: for a missing file.
        ValueError: for a malformed graph, naming the file, the key and the value.
    """
    if isinstance(source, Mapping):
        if "levels" in source:
            return route_graph_from_rmf(source)
        if "layouts" in source:
            return route_graph_from_lif(source, layout_id=layout_id, vehicle_type=vehicle_type)
        return route_graph_from_mapping(source)
    path = Path(source)
    if path.suffix.lower() in (".json", ".lif"):
        if not path.is_file():
            raise FileNotFoundError(f"route graph: no file {path.resolve()}")
        try:
            data = json.loads(path.read_text())
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}: not JSON ({exc})") from None
        return route_graph_from_lif(
            data, layout_id=layout_id, vehicle_type=vehicle_type, source=str(path)
        )
    data = load_yaml_config(path, allow_empty=False)
    if isinstance(data, Mapping) and "levels" in data:  # an Open-RMF nav graph
        return route_graph_from_rmf(data, source=str(path))
    return route_graph_from_mapping(data, source=str(path))


def _where(source: str | None) -> str:
    return f"{source}: " if source else ""


def _keys(entry: Any, allowed: set[str], what: str, source: str | None) -> Mapping[str, Any]:
    if not isinstance(entry, Mapping):
        raise ValueError(f"{_where(source)}{what}: expected a mapping, got {entry!r}")
    unknown = sorted(set(entry) - allowed)
    if unknown:
        raise ValueError(
            f"{_where(source)}{what}: unknown key {unknown[0]!r} (expected {sorted(allowed)})"
        )
    return entry


def _number(value: Any, key: str, what: str, source: str | None, optional: bool = False) -> Any:
    if value is None and optional:
        return None
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok:
        raise ValueError(f"{_where(source)}{what}.{key}: expected a number, got {value!r}")
    return float(value)


def _text(value: Any, key: str, what: str, source: str | None) -> str:
    if isinstance(value, (int, str)) and not isinstance(value, bool) and str(value):
        return str(value)
    raise ValueError(f"{_where(source)}{what}.{key}: expected an id, got {value!r}")


def route_graph_from_mapping(data: Mapping[str, Any], source: str | None = None) -> RouteGraph:
    """A route graph from the YAML graph's mapping (see the module doc)."""
    _keys(data, _TOP, "route graph", source)
    graph = RouteGraph(
        _number(data.get("default_speed", 1.0), "default_speed", "route graph", source)
    )
    map_id = data.get("map_id")
    nodes, edges = data.get("nodes") or [], data.get("edges") or []
    if not isinstance(nodes, list) or not isinstance(edges, list):
        raise ValueError(f"{_where(source)}route graph: nodes and edges must be lists")
    try:
        for i, raw in enumerate(nodes):
            what = f"nodes[{i}]"
            entry = _keys(raw, _NODE, what, source)
            graph.add_node(
                RouteNode(
                    _text(entry.get("id"), "id", what, source),
                    _number(entry.get("x"), "x", what, source),
                    _number(entry.get("y"), "y", what, source),
                    _number(entry.get("theta"), "theta", what, source, optional=True),
                    entry.get("map_id", map_id),
                )
            )
        for i, raw in enumerate(edges):
            what = f"edges[{i}]"
            entry = _keys(raw, _EDGE, what, source)
            edge_id = _text(entry.get("id"), "id", what, source)
            start = _text(entry.get("from"), "from", what, source)
            end = _text(entry.get("to"), "to", what, source)
            speed = _number(entry.get("max_speed"), "max_speed", what, source, optional=True)
            graph.add_edge(edge_id, start, end, speed)
            both = entry.get("bidirectional", False)
            if not isinstance(both, bool):
                raise ValueError(
                    f"{_where(source)}{what}.bidirectional: expected true or false, got {both!r}"
                )
            if both:
                reverse = entry.get("reverse_id", f"{edge_id}~")
                graph.add_edge(_text(reverse, "reverse_id", what, source), end, start, speed)
    except ValueError as exc:
        if source and not str(exc).startswith(source):
            raise ValueError(f"{source}: {exc}") from None
        raise
    return graph


def _vehicle_props(
    entry: Mapping[str, Any], key: str, vehicle_type: str | None
) -> Mapping[str, Any]:
    props = entry.get(key) or []
    if not isinstance(props, list):
        return {}
    for prop in props:
        if isinstance(prop, Mapping) and (
            vehicle_type is None or prop.get("vehicleTypeId") == vehicle_type
        ):
            return prop
    return {}


def route_graph_from_lif(
    data: Any,
    *,
    layout_id: str | None = None,
    vehicle_type: str | None = None,
    source: str | None = None,
) -> RouteGraph:
    """A route graph from a LIF document (see the module doc)."""
    if not isinstance(data, Mapping) or not isinstance(data.get("layouts"), list):
        raise ValueError(f"{_where(source)}LIF: expected an object with a list of layouts")
    layouts = [lay for lay in data["layouts"] if isinstance(lay, Mapping)]
    if layout_id is not None:
        layouts = [lay for lay in layouts if lay.get("layoutId") == layout_id]
        if not layouts:
            raise ValueError(f"{_where(source)}LIF: no layout {layout_id!r}")
    elif len(layouts) != 1:
        ids = [lay.get("layoutId") for lay in layouts]
        raise ValueError(
            f"{_where(source)}LIF: {len(layouts)} layouts {ids}; choose one with layout_id"
        )
    layout = layouts[0]
    level = layout.get("layoutLevelId")
    graph = RouteGraph()
    for i, node in enumerate(layout.get("nodes") or []):
        what = f"layouts[{layout.get('layoutId')!r}].nodes[{i}]"
        if not isinstance(node, Mapping):
            raise ValueError(f"{_where(source)}{what}: expected an object, got {node!r}")
        pos = node.get("nodePosition") or {}
        theta = _vehicle_props(node, "vehicleTypeNodeProperties", vehicle_type).get("theta")
        graph.add_node(
            RouteNode(
                _text(node.get("nodeId"), "nodeId", what, source),
                _number(pos.get("x"), "nodePosition.x", what, source),
                _number(pos.get("y"), "nodePosition.y", what, source),
                _number(theta, "theta", what, source, optional=True),
                None if level is None else str(level),
            )
        )
    for i, edge in enumerate(layout.get("edges") or []):
        what = f"layouts[{layout.get('layoutId')!r}].edges[{i}]"
        if not isinstance(edge, Mapping):
            raise ValueError(f"{_where(source)}{what}: expected an object, got {edge!r}")
        speed = _vehicle_props(edge, "vehicleTypeEdgeProperties", vehicle_type).get("maxSpeed")
        try:
            graph.add_edge(
                _text(edge.get("edgeId"), "edgeId", what, source),
                _text(edge.get("startNodeId"), "startNodeId", what, source),
                _text(edge.get("endNodeId"), "endNodeId", what, source),
                _number(speed, "maxSpeed", what, source, optional=True),
            )
        except ValueError as exc:
            raise ValueError(f"{_where(source)}{what}: {exc}") from None
    return graph
