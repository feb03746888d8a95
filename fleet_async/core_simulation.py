"""The simulation and its settings.

The reference API's ``core_simulation`` module: a thin facade over the modules of the core that
own these names, so a pybullet_fleet script ports by renaming its import
(``pybullet_fleet.core_simulation`` becomes ``fleet_async.core_simulation``). Nothing in
fleet_async imports this module.
"""

from __future__ import annotations

from fleet_async.core.base.params import SimulationParams
from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["MultiRobotSimulationCore", "SimulationParams"]
