"""Route graphs: nodes and edges with ids, positions and speed limits (LIF and YAML), the
quickest route to a node, and who is on which edge (``docs/traffic.md``)."""

from fleet_async.core.routes.follow import FollowRouteAction, RouteLeg, route_to_node
from fleet_async.core.routes.graph import RouteEdge, RouteGraph, RouteNode
from fleet_async.core.routes.loaders import load_route_graph

__all__ = [
    "FollowRouteAction",
    "RouteEdge",
    "RouteGraph",
    "RouteLeg",
    "RouteNode",
    "load_route_graph",
    "route_to_node",
]
