"""The simulation's route graph: ``sim.load_route_graph(...)``, ``sim.route_graph``.

Mixed into ``MultiRobotSimulationCore``. One graph per simulation (the roadmap its robots'
``go_to_node`` plans on); loading another replaces it.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from fleet_async.core.routes.graph import RouteGraph
from fleet_async.core.routes.loaders import load_route_graph

__all__ = ["RoutesApi", "graph_of"]


class RoutesApi:
    """``sim.route_graph`` and ``sim.load_route_graph`` (mixed into the simulation)."""

    _route_graph: RouteGraph | None = None

    @property
    def route_graph(self) -> RouteGraph | None:
        """The route graph robots plan ``go_to_node`` on, or None before one is loaded."""
        return self._route_graph

    def set_route_graph(self, graph: RouteGraph | None) -> None:
        """Use ``graph`` (None: none) from now on.

        Raises:
            TypeError: for anything but a RouteGraph or None.
        """
        if graph is not None and not isinstance(graph, RouteGraph):
            raise TypeError(f"set_route_graph: expected a RouteGraph or None, got {graph!r}")
        self._route_graph = graph
        self._trace_graph(graph)

    def load_route_graph(
        self,
        source: str | os.PathLike[str] | Mapping[str, Any],
        *,
        layout_id: str | None = None,
        vehicle_type: str | None = None,
    ) -> RouteGraph:
        """Load a YAML graph, an Open-RMF nav graph or a LIF layout (``routes/loaders.py``)
        and use it; return it."""
        graph = load_route_graph(source, layout_id=layout_id, vehicle_type=vehicle_type)
        self._route_graph = graph
        self._trace_graph(graph)
        return graph

    def _trace_graph(self, graph: RouteGraph | None) -> None:
        """Log the graph now in use in a running trace (``route_graph``; no nodes: none)."""
        trace_event = getattr(self, "trace_event", None)
        if trace_event is not None:
            data = graph.trace_data() if graph is not None else {"nodes": [], "edges": []}
            trace_event("route_graph", None, **data)


def graph_of(agent: Any) -> RouteGraph:
    """The route graph of ``agent``'s simulation.

    Raises:
        RuntimeError: when the agent is in no simulation or its simulation has no graph.
    """
    sim = agent.sim_core
    graph = getattr(sim, "route_graph", None) if sim is not None else None
    if graph is None:
        raise RuntimeError(
            f"go_to_node: {agent!r} has no route graph: load one first "
            "(sim.load_route_graph(path) or the scenario's route_graph key)"
        )
    return graph
