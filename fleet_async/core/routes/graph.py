"""RouteGraph: nodes and directed edges with ids, positions and speed limits.

A route graph is the roadmap a fleet drives on (a LIF layout, an Open-RMF nav graph, a
hand-written YAML graph): nodes with ids and positions (m, world frame; an optional heading),
directed edges with ids, a length (the straight line between their nodes) and an optional
speed limit (m/s). Shortest paths are by travel time where edges have speed limits and by
length otherwise (an edge without a limit counts at ``default_speed``); ties are broken by
node id, so the same graph gives the same path on every run.

The graph also tells traffic control who is where (:meth:`RouteGraph.locate`,
:meth:`RouteGraph.occupancy`); it reserves nothing: reservations are the fleet's own job.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["RouteEdge", "RouteGraph", "RouteNode"]


@dataclass(frozen=True)
class RouteNode:
    """A node of a route graph.

    Attributes:
        node_id: Unique id.
        x, y: Position (m, world frame).
        theta: Heading a vehicle should have there (rad), or None for any.
        map_id: The map (layout level) the node is on, or None.
    """

    node_id: str
    x: float
    y: float
    theta: float | None = None
    map_id: str | None = None


@dataclass(frozen=True)
class RouteEdge:
    """A directed edge of a route graph (``start`` to ``end``).

    Attributes:
        edge_id: Unique id.
        start, end: Node ids.
        max_speed: Speed limit on the edge (m/s), or None for none.
        length: Straight-line length between the two nodes (m).
    """

    edge_id: str
    start: str
    end: str
    max_speed: float | None = None
    length: float = 0.0


class RouteGraph:
    """Nodes and directed edges; build with :meth:`add_node` / :meth:`add_edge` or a loader
    (``routes.loaders``).

    Args:
        default_speed: Speed (m/s) at which an edge without a limit counts in shortest paths.
    """

    def __init__(self, default_speed: float = 1.0) -> None:
        if not (isinstance(default_speed, (int, float)) and default_speed > 0):
            raise ValueError(
                f"RouteGraph.default_speed: expected a number > 0 (m/s), got {default_speed!r}"
            )
        self.default_speed = float(default_speed)
        self.nodes: dict[str, RouteNode] = {}
        self.edges: dict[str, RouteEdge] = {}
        self._out: dict[str, list[RouteEdge]] = {}
        self._arrays: tuple[np.ndarray, np.ndarray, list[str]] | None = None

    def __repr__(self) -> str:
        return f"RouteGraph({len(self.nodes)} nodes, {len(self.edges)} edges)"

    # ----- building -------------------------------------------------------------------------

    def trace_data(self) -> dict[str, Any]:
        """The graph for the trace's ``route_graph`` event: ``nodes`` as ``[id, x, y]`` (m,
        rounded to mm) and directed ``edges`` as ``[id, start, end]``."""
        nodes = [[n.node_id, round(n.x, 3), round(n.y, 3)] for n in self.nodes.values()]
        edges = [[e.edge_id, e.start, e.end] for e in self.edges.values()]
        return {"nodes": nodes, "edges": edges}

    def add_node(self, node: RouteNode) -> RouteNode:
        """Add ``node``.

        Raises:
            ValueError: for a repeated id or a position that is not finite.
        """
        if node.node_id in self.nodes:
            raise ValueError(f"route graph: node {node.node_id!r} is defined twice")
        if not (math.isfinite(node.x) and math.isfinite(node.y)):
            raise ValueError(f"route graph: node {node.node_id!r} has no finite position")
        self.nodes[node.node_id] = node
        self._out[node.node_id] = []
        self._arrays = None
        return node

    def add_edge(
        self, edge_id: str, start: str, end: str, max_speed: float | None = None
    ) -> RouteEdge:
        """Add the directed edge ``start`` -> ``end``; return it.

        Raises:
            ValueError: for a repeated id, an unknown node or a bad speed limit.
        """
        if edge_id in self.edges:
            raise ValueError(f"route graph: edge {edge_id!r} is defined twice")
        for end_name, node_id in (("start", start), ("end", end)):
            if node_id not in self.nodes:
                raise ValueError(
                    f"route graph: edge {edge_id!r} {end_name}s at unknown node {node_id!r}"
                )
        if max_speed is not None and not (
            isinstance(max_speed, (int, float)) and not isinstance(max_speed, bool)
        ):
            raise ValueError(f"route graph: edge {edge_id!r} max_speed {max_speed!r} is no number")
        if max_speed is not None and not max_speed > 0:
            raise ValueError(f"route graph: edge {edge_id!r} max_speed {max_speed!r} is not > 0")
        a, b = self.nodes[start], self.nodes[end]
        edge = RouteEdge(
            edge_id,
            start,
            end,
            None if max_speed is None else float(max_speed),
            math.hypot(b.x - a.x, b.y - a.y),
        )
        self.edges[edge_id] = edge
        self._out[start].append(edge)
        self._arrays = None
        return edge

    # ----- queries ----------------------------------------------------------------------------

    def node(self, node_id: str) -> RouteNode:
        """The node ``node_id``.

        Raises:
            KeyError: naming the id, for an unknown node.
        """
        try:
            return self.nodes[node_id]
        except KeyError:
            raise KeyError(f"route graph: no node {node_id!r}") from None

    def edges_from(self, node_id: str) -> list[RouteEdge]:
        """Edges leaving ``node_id``, in the order they were added."""
        return list(self._out[self.node(node_id).node_id])

    def cost(self, edge: RouteEdge) -> float:
        """The edge's weight in shortest paths: its travel time (s) at its limit."""
        return edge.length / (edge.max_speed or self.default_speed)

    def shortest_path(self, start: str, goal: str) -> list[RouteEdge]:
        """The edges of a quickest route from node ``start`` to node ``goal`` ([] if equal).

        Raises:
            KeyError: for an unknown node.
            ValueError: when ``goal`` cannot be reached from ``start``.
        """
        self.node(start)
        self.node(goal)
        best: dict[str, float] = {start: 0.0}
        via: dict[str, RouteEdge] = {}
        queue: list[tuple[float, str]] = [(0.0, start)]
        done: set[str] = set()
        while queue:
            cost, here = heapq.heappop(queue)
            if here in done:
                continue
            if here == goal:
                break
            done.add(here)
            for edge in self._out[here]:
                total = cost + self.cost(edge)
                if total < best.get(edge.end, math.inf) - 1e-12:
                    best[edge.end] = total
                    via[edge.end] = edge
                    heapq.heappush(queue, (total, edge.end))
        if goal != start and goal not in via:
            raise ValueError(f"route graph: node {goal!r} cannot be reached from {start!r}")
        path: list[RouteEdge] = []
        node = goal
        while node != start:
            edge = via[node]
            path.append(edge)
            node = edge.start
        return path[::-1]

    def nearest_node(self, x: float, y: float) -> RouteNode:
        """The node closest to (x, y) (the first by id among equally close ones).

        Raises:
            ValueError: for an empty graph.
        """
        if not self.nodes:
            raise ValueError("route graph: it has no nodes")
        return min(self.nodes.values(), key=lambda n: ((n.x - x) ** 2 + (n.y - y) ** 2, n.node_id))

    def _edge_arrays(self) -> tuple[np.ndarray, np.ndarray, list[str]]:
        if self._arrays is None:
            ids = list(self.edges)
            a = np.array(
                [[self.nodes[e.start].x, self.nodes[e.start].y] for e in self.edges.values()]
            )
            b = np.array([[self.nodes[e.end].x, self.nodes[e.end].y] for e in self.edges.values()])
            self._arrays = (a.reshape(-1, 2), b.reshape(-1, 2), ids)
        return self._arrays

    def locate(
        self, positions: Sequence[Sequence[float]] | np.ndarray, tolerance: float = 0.25
    ) -> list[str | None]:
        """The edge each (x, y) position lies on, within ``tolerance`` metres of it.

        A position near several edges (a node, two directions of one lane) is on the first
        of them in the order they were added. None where no edge is that close.
        """
        pts = np.asarray(positions, dtype=float).reshape(-1, 2)
        a, b, ids = self._edge_arrays()
        if not len(ids) or not len(pts):
            return [None] * len(pts)
        out: list[str | None] = []
        ab = b - a
        denom = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18)
        for chunk in range(0, len(pts), 256):  # (chunk, edges) at a time bounds the memory
            p = pts[chunk : chunk + 256, None, :]
            t = np.clip(np.einsum("kij,ij->ki", p - a, ab) / denom, 0.0, 1.0)
            d2 = np.sum((a + t[..., None] * ab - p) ** 2, axis=2)
            near = d2 <= tolerance * tolerance
            first = np.argmax(near, axis=1)
            hit = near[np.arange(len(first)), first]
            out += [
                ids[i] if h else None for i, h in zip(first.tolist(), hit.tolist(), strict=True)
            ]
        return out

    def occupancy(self, agents: Iterable[Any], tolerance: float = 0.25) -> dict[str, list[Any]]:
        """``{edge_id: agents on it}`` for the edges with someone on them (see :meth:`locate`).

        Args:
            agents: Anything with ``get_pose()`` (robots), in the order to list them.
            tolerance: How far from an edge (m) an agent still counts as on it.
        """
        agents = list(agents)
        positions = [agent.get_pose().position[:2] for agent in agents]
        out: dict[str, list[Any]] = {}
        for agent, edge in zip(agents, self.locate(positions, tolerance), strict=True):
            if edge is not None:
                out.setdefault(edge, []).append(agent)
        return out
