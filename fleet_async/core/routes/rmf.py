"""Route graphs from Open-RMF nav graphs (the YAML that Open-RMF's building map generator
writes for a fleet, one per graph index, and fleet adapters read).

The file's shape::

    building_name: office               # optional
    levels:
      L1:
        vertices:                       # [x, y, {name: ..., other vertex parameters}]
          - [3.0, -2.0, {name: charger_1, is_charger: true}]
          - [8.0, -2.0, {name: ""}]
        lanes:                          # [start vertex, end vertex, {lane parameters}]
          - [0, 1, {speed_limit: 0.5}]
          - [1, 0, {is_bidirectional: true, orientation_constraint: forward}]

Vertices index into their level's list. A vertex with a ``name`` becomes the node of that id
(names are unique in a file), one without a name ``{level}#{index}``; every node's ``map_id``
is its level. A lane is a directed edge ``{start node}>{end node}``; with ``is_bidirectional``
true, its reverse is added too (the generator writes each direction as a lane of its own by
default). ``speed_limit`` > 0 is the edge's ``max_speed`` (0 means none). Other vertex and lane
parameters (chargers, docks, doors, lifts, mutexes, orientation constraints) and the file's
``doors`` / ``lifts`` sections are not read: the route graph has no notion of them.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from fleet_async.core.routes.graph import RouteGraph, RouteNode

__all__ = ["route_graph_from_rmf"]


def _fail(source: str | None, where: str, message: str) -> ValueError:
    return ValueError(f"{source + ': ' if source else ''}Open-RMF nav graph: {where}: {message}")


def _number(value: Any, source: str | None, where: str) -> float:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    raise _fail(source, where, f"expected a number, got {value!r}")


def _params(entry: list[Any], size: int, source: str | None, where: str) -> Mapping[str, Any]:
    """The parameter mapping at ``entry[size]`` ({} when the entry has none)."""
    if not isinstance(entry, list) or len(entry) not in (size, size + 1):
        raise _fail(source, where, f"expected {size} values and parameters, got {entry!r}")
    params = entry[size] if len(entry) > size else {}
    if params is None:
        return {}
    if not isinstance(params, Mapping):
        raise _fail(source, where, f"expected a mapping of parameters, got {params!r}")
    return params


def _level_nodes(graph: RouteGraph, level: str, vertices: Any, source: str | None) -> list[str]:
    """Add a level's vertices as nodes; return their ids by index."""
    if not isinstance(vertices, list):
        raise _fail(source, f"levels.{level}.vertices", f"expected a list, got {vertices!r}")
    ids = []
    for i, vertex in enumerate(vertices):
        where = f"levels.{level}.vertices[{i}]"
        params = _params(vertex, 2, source, where)
        x, y = _number(vertex[0], source, f"{where}.x"), _number(vertex[1], source, f"{where}.y")
        name = params.get("name")
        node_id = str(name) if name not in (None, "") else f"{level}#{i}"
        if node_id in graph.nodes:
            raise _fail(source, where, f"the vertex name {node_id!r} is used twice")
        graph.add_node(RouteNode(node_id, x, y, map_id=level))
        ids.append(node_id)
    return ids


def route_graph_from_rmf(
    data: Mapping[str, Any], source: str | None = None, default_speed: float = 1.0
) -> RouteGraph:
    """A route graph from an Open-RMF nav graph's mapping (see the module doc).

    Args:
        data: The file's mapping (with ``levels``).
        source: The file, for messages.
        default_speed: m/s at which lanes without a speed limit count in shortest paths.

    Raises:
        ValueError: for a malformed graph, naming the file, the level, the entry and the value.
    """
    levels = data.get("levels")
    if not isinstance(levels, Mapping) or not levels:
        raise _fail(source, "levels", f"expected a mapping of levels, got {levels!r}")
    graph = RouteGraph(default_speed)
    for level, content in levels.items():
        if not isinstance(content, Mapping):
            raise _fail(source, f"levels.{level}", f"expected a mapping, got {content!r}")
        ids = _level_nodes(graph, str(level), content.get("vertices") or [], source)
        lanes = content.get("lanes") or []
        if not isinstance(lanes, list):
            raise _fail(source, f"levels.{level}.lanes", f"expected a list, got {lanes!r}")
        for k, lane in enumerate(lanes):
            where = f"levels.{level}.lanes[{k}]"
            params = _params(lane, 2, source, where)
            ends = []
            for end in lane[:2]:
                if not (isinstance(end, int) and not isinstance(end, bool) and 0 <= end < len(ids)):
                    raise _fail(source, where, f"no vertex {end!r} (the level has {len(ids)})")
                ends.append(ids[end])
            limit = _number(params.get("speed_limit", 0.0), source, f"{where}.speed_limit")
            speed = limit if limit > 0 else None
            directions = [(ends[0], ends[1])]
            if params.get("is_bidirectional") is True:
                directions.append((ends[1], ends[0]))
            for start, end in directions:
                edge_id = f"{start}>{end}"
                if edge_id in graph.edges:  # two lanes between the same vertices
                    edge_id = f"{edge_id}#{k}"
                graph.add_edge(edge_id, start, end, speed)
    return graph
