"""Loading YAML configuration and mapping it onto dataclasses.

The reference API's ``config_utils`` module: a thin facade over the modules of the core that own
these names, so a pybullet_fleet script ports by renaming its import
(``pybullet_fleet.config_utils`` becomes ``fleet_async.config_utils``). Nothing in fleet_async
imports this module.
"""

from __future__ import annotations

from fleet_async.core.base.config_utils import (
    dataclass_from_dict,
    forward_spawn_params,
    load_config,
    load_yaml_config,
    merge_configs,
    resolve_class,
)

__all__ = [
    "dataclass_from_dict",
    "forward_spawn_params",
    "load_config",
    "load_yaml_config",
    "merge_configs",
    "resolve_class",
]
