"""The live data monitor.

The reference API's ``data_monitor`` module: a thin facade over the modules of the core that own
these names, so a pybullet_fleet script ports by renaming its import
(``pybullet_fleet.data_monitor`` becomes ``fleet_async.data_monitor``). Nothing in fleet_async
imports this module.

The reference's ``main()`` (a standalone monitor) has no counterpart here: the monitor window
is a child process that ``DataMonitor`` starts and feeds.
"""

from __future__ import annotations

from fleet_async.core.view.monitor import DataMonitor

__all__ = ["DataMonitor"]
