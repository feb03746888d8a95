"""The scenario's ``traffic:`` section: route graph, grid maps, deadlock watch.

::

    traffic:
      route_graph: layout.lif.json      # or {path, layout_id, vehicle_type}
      maps:                             # map_server .yaml or MovingAI .map files
        - warehouse.map                 # or {path, resolution, height, tile}
      deadlock_after: 10.0              # s (sim.safety.deadlock_after)

Paths are relative to the scenario file. Safety fields are per robot: the entities'
``safety_field`` key (``AgentSpawnParams.safety_field``). Every error names the key, the
value and the file.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fleet_async.core.scenario.errors import config_context, expect_type, reject_unknown_keys

__all__ = ["TRAFFIC_KEYS", "apply_traffic"]

TRAFFIC_KEYS = ("route_graph", "maps", "deadlock_after")
_GRAPH_KEYS = ("path", "layout_id", "vehicle_type")
_MAP_KEYS = ("path", "resolution", "height", "tile")


def _options(entry: Any, keys: tuple[str, ...], where: str, label: str) -> dict[str, Any]:
    options = {"path": entry} if isinstance(entry, (str, os.PathLike)) else entry
    expect_type(options, Mapping, f"a path or a mapping {{{', '.join(keys)}}}", where, label)
    reject_unknown_keys(list(options), keys, where, label)
    expect_type(options.get("path"), (str, os.PathLike), "a file path", where, f"{label}.path")
    return dict(options)


def _resolve(path: Any, base_dir: str | os.PathLike[str] | None) -> Path:
    found = Path(path).expanduser()
    if not found.is_absolute() and base_dir is not None and (Path(base_dir) / found).exists():
        return Path(base_dir) / found
    return found


def apply_traffic(
    sim: Any, section: Mapping[str, Any], where: str, base_dir: str | os.PathLike[str] | None
) -> None:
    """Load the section's maps and route graph into ``sim`` and set its deadlock time."""
    expect_type(section, Mapping, "a mapping", where, "traffic")
    reject_unknown_keys(list(section), TRAFFIC_KEYS, where, "traffic")
    maps = section.get("maps") or []
    expect_type(maps, list, "a list of map files", where, "traffic.maps")
    for i, entry in enumerate(maps):
        label = f"traffic.maps[{i}]"
        options = _options(entry, _MAP_KEYS, where, label)
        path = _resolve(options.pop("path"), base_dir)
        with config_context(where, label):
            sim.load_map(path, **options)
    if section.get("route_graph") is not None:
        options = _options(section["route_graph"], _GRAPH_KEYS, where, "traffic.route_graph")
        path = _resolve(options.pop("path"), base_dir)
        with config_context(where, "traffic.route_graph"):
            sim.load_route_graph(path, **options)
    if "deadlock_after" in section:
        with config_context(where, "traffic.deadlock_after"):
            sim.safety.deadlock_after = section["deadlock_after"]
