"""Simulation events: the event bus and the names of the events the simulator emits.

pybullet_fleet's ``events`` module (its scripts, and the reference API's own ``SimObject.events``
example, import ``SimEvents`` from ``pybullet_fleet.events``): a thin facade over the module of
the core that owns these names, so such a script ports by renaming its import
(``pybullet_fleet.events`` becomes ``fleet_async.events``). Nothing in fleet_async imports this
module.
"""

from __future__ import annotations

from fleet_async.core.base.events import EventBus, SimEvents

__all__ = ["EventBus", "SimEvents"]
