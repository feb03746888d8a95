"""Agents and what it takes to spawn one.

The reference API's ``agent`` module: a thin facade over the modules of the core that own these
names, so a pybullet_fleet script ports by renaming its import (``pybullet_fleet.agent`` becomes
``fleet_async.agent``). Nothing in fleet_async imports this module.
"""

from __future__ import annotations

from fleet_async.core.agents.agent import Agent
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.motion.ik import IKParams

__all__ = ["Agent", "AgentSpawnParams", "IKParams"]
