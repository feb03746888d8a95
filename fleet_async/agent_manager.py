"""Managers of objects and agents, and grid spawning.

The reference API's ``agent_manager`` module: a thin facade over the modules of the core that
own these names, so a pybullet_fleet script ports by renaming its import
(``pybullet_fleet.agent_manager`` becomes ``fleet_async.agent_manager``). Nothing in fleet_async
imports this module.
"""

from __future__ import annotations

from fleet_async.core.managers.agent_manager import AgentManager
from fleet_async.core.managers.grid_spawn import GridSpawnParams
from fleet_async.core.managers.sim_object_manager import SimObjectManager

__all__ = ["AgentManager", "GridSpawnParams", "SimObjectManager"]
