"""A grid map in a simulation: static collision geometry merged into few bodies.

The occupied cells become rectangles (``OccupancyGrid.rectangles``), the rectangles boxes of
``height`` metres, and the boxes are grouped by square tiles of ``tile`` metres (a box belongs
to the tile of its centre) into one STATIC PyBullet body per tile, each a compound of its boxes:
a warehouse map of thousands of cells is a few dozen bodies, and each body's AABB stays local,
so the collision broad phase still culls. The safety fields see the boxes themselves
(``sim.safety.add_static_boxes``), not the tiles' AABBs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pybullet as p

from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.maps.grid import OccupancyGrid

__all__ = ["GridMap", "add_grid_map"]

_MAX_BOXES = 256  # boxes per compound body (PyBullet builds big compounds slowly)
_COLOUR = (0.35, 0.35, 0.4, 1.0)


@dataclass
class GridMap:
    """A grid map added to a simulation.

    Attributes:
        grid: The occupancy grid.
        bodies: Its static bodies (one per tile).
        lo, hi: (K, 3) world corners (m) of its obstacle boxes.
    """

    grid: OccupancyGrid
    bodies: list[SimObject] = field(default_factory=list)
    lo: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    hi: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    def trace_data(self) -> dict[str, Any]:
        """The map for the trace's ``map_loaded`` event: ``name``, ``rects`` (its obstacle
        boxes seen from above, ``[x0, y0, x1, y1]`` in m, world frame) and ``bodies`` (the
        object ids of its tile bodies, which the viewer draws as these rectangles)."""
        rects = np.round(np.column_stack((self.lo[:, :2], self.hi[:, :2])), 4).tolist()
        name = (self.bodies[0].name or "map").rsplit("[", 1)[0] if self.bodies else "map"
        return {"name": name, "rects": rects, "bodies": [b.object_id for b in self.bodies]}

    def free_cells(self) -> np.ndarray:
        """(K, 2) (row, col) of every free cell, row by row."""
        return np.argwhere(~self.grid.occupied)

    def cell_position(self, row: int, col: int, z: float = 0.0) -> tuple[float, float, float]:
        """World (x, y, z) of the centre of cell (row, col)."""
        x, y = self.grid.cell_center(row, col)
        return x, y, z


def _tiles(lo: np.ndarray, hi: np.ndarray, tile: float) -> list[np.ndarray]:
    """Box indices grouped by the tile of their centres (each group at most _MAX_BOXES)."""
    centre = 0.5 * (lo[:, :2] + hi[:, :2])
    key = np.floor(centre / tile).astype(np.int64)
    order = np.lexsort((key[:, 0], key[:, 1]))
    groups: list[np.ndarray] = []
    if not len(order):
        return groups
    k = key[order]
    cut = np.flatnonzero(np.any(k[1:] != k[:-1], axis=1)) + 1
    for part in np.split(order, cut):
        groups += [part[i : i + _MAX_BOXES] for i in range(0, len(part), _MAX_BOXES)]
    return groups


def add_grid_map(
    sim: Any,
    grid: OccupancyGrid,
    *,
    height: float = 1.0,
    tile: float = 10.0,
    name: str = "map",
) -> GridMap:
    """Add ``grid``'s occupied cells to ``sim`` as static bodies (see the module doc); the
    simulation keeps the map in ``sim.maps`` and logs it to a running trace (``map_loaded``).

    Args:
        sim: The simulation.
        grid: The map.
        height: Height of the obstacle boxes (m, from z = 0).
        tile: Edge of the square tiles (m) whose boxes share a body.
        name: Bodies are named ``{name}[i]``.

    Raises:
        ValueError: for a height or tile that is not a number > 0.
    """
    for key, value in (("height", height), ("tile", tile)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"add_grid_map: {key}: expected a number > 0 (m), got {value!r}")
    lo, hi = grid.boxes(0.0, float(height))
    result = GridMap(grid, [], lo, hi)
    client = sim.world.client
    for i, group in enumerate(_tiles(lo, hi, float(tile))):
        half = (0.5 * (hi[group] - lo[group])).tolist()
        centre = 0.5 * (hi[group] + lo[group])
        base = centre.mean(axis=0)
        frames = (centre - base).tolist()
        count = len(group)
        shape = p.createCollisionShapeArray(
            shapeTypes=[p.GEOM_BOX] * count,
            halfExtents=half,
            collisionFramePositions=frames,
            physicsClientId=client,
        )
        visual = p.createVisualShapeArray(
            shapeTypes=[p.GEOM_BOX] * count,
            halfExtents=half,
            visualFramePositions=frames,
            rgbaColors=[_COLOUR] * count,
            physicsClientId=client,
        )
        body = p.createMultiBody(
            baseMass=0.0,
            baseCollisionShapeIndex=shape,
            baseVisualShapeIndex=visual,
            basePosition=base.tolist(),
            physicsClientId=client,
        )
        obj = SimObject(
            body, sim, pickable=False, mass=0.0, collision_mode="static", name=f"{name}[{i}]"
        )
        result.bodies.append(obj)
    if len(lo):
        sim.safety.add_static_boxes(lo, hi, replaces=result.bodies)
    note = getattr(sim, "note_map", None)
    if note is not None:  # the simulation keeps it and traces it (maps/api.py)
        note(result)
    return result
