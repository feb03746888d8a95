"""``sim.load_map(path)``: a map_server occupancy grid or a MovingAI map as static geometry.

Mixed into ``MultiRobotSimulationCore``; the maps added (``load_map``, ``add_map`` or
``add_grid_map``) are kept in ``sim.maps`` and logged to the trace.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from fleet_async.core.maps.grid import OccupancyGrid
from fleet_async.core.maps.readers import read_map_server, read_movingai_map
from fleet_async.core.maps.world import GridMap, add_grid_map

__all__ = ["MapsApi"]


class MapsApi:
    """``sim.load_map``, ``sim.add_map`` and ``sim.maps`` (mixed into the simulation)."""

    _maps: list[GridMap] | None = None

    @property
    def maps(self) -> list[GridMap]:
        """The grid maps loaded, in order."""
        return list(self._maps or [])

    def load_map(
        self,
        path: str | os.PathLike[str],
        *,
        resolution: float = 1.0,
        height: float = 1.0,
        tile: float = 10.0,
    ) -> GridMap:
        """Load a map_server YAML map (``.yaml`` / ``.yml``) or a MovingAI ``.map`` as static
        obstacles (``maps/world.py``).

        Args:
            path: The map file.
            resolution: Cell edge (m) of a MovingAI map (map_server maps state their own).
            height: Height of the obstacles (m).
            tile: Edge of the tiles (m) whose obstacles share a body.

        Raises:
            FileNotFoundError: for a missing file.
            ValueError: for an unknown kind of file or a malformed map, naming the file.
        """
        source = Path(path)
        if not source.is_file():
            raise FileNotFoundError(f"load_map: no file {source.resolve()}")
        suffix = source.suffix.lower()
        if suffix in (".yaml", ".yml"):
            grid = read_map_server(source)
        elif suffix == ".map":
            grid = read_movingai_map(source, resolution)
        else:
            raise ValueError(
                f"load_map: {source}: expected a map_server .yaml or a MovingAI .map file"
            )
        return add_grid_map(self, grid, height=height, tile=tile, name=source.stem)

    def add_map(
        self, grid: OccupancyGrid, *, height: float = 1.0, tile: float = 10.0, name: str = "map"
    ) -> GridMap:
        """Add an occupancy grid made in code as static obstacles (``add_grid_map``)."""
        return add_grid_map(self, grid, height=height, tile=tile, name=name)

    def note_map(self, loaded: GridMap) -> None:
        """Keep ``loaded`` in ``sim.maps`` and log it to a running trace (``map_loaded``):
        ``add_grid_map`` calls it for every map it adds, however it was asked to."""
        self._maps = [*(self._maps or []), loaded]
        trace_event = getattr(self, "trace_event", None)
        if trace_event is not None:  # a running trace draws it (docs/trace-format.md)
            trace_event("map_loaded", None, **loaded.trace_data())

    def trace_scenery(self) -> list[tuple[str, dict[str, Any]]]:
        """The ``map_loaded`` and ``route_graph`` events a trace starts with (the maps loaded
        and the route graph in use), as ``(kind, data)``."""
        events: list[tuple[str, dict[str, Any]]] = [
            ("map_loaded", m.trace_data()) for m in self._maps or []
        ]
        graph = getattr(self, "route_graph", None)
        if graph is not None:
            events.append(("route_graph", graph.trace_data()))
        return events
