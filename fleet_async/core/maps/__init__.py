"""Grid maps: map_server occupancy grids and MovingAI maps as static collision geometry
(``docs/traffic.md``)."""

from fleet_async.core.maps.grid import OccupancyGrid
from fleet_async.core.maps.readers import (
    MovingAiTask,
    read_map_server,
    read_movingai_map,
    read_movingai_scen,
)
from fleet_async.core.maps.world import GridMap, add_grid_map

__all__ = [
    "GridMap",
    "MovingAiTask",
    "OccupancyGrid",
    "add_grid_map",
    "read_map_server",
    "read_movingai_map",
    "read_movingai_scen",
]
