"""fleet_async: a kinematics-first multi-robot fleet simulator on PyBullet.

The public API mirrors pybullet_fleet's (``MultiRobotSimulationCore``, ``SimulationParams``,
``SimObject``, ``Pose``, ``Path``, ...). Everything listed in ``__all__`` is importable from
here; submodules live in ``fleet_async.core`` (the synchronous simulator) and
``fleet_async.tasks`` (async missions, and their sim-aware Event, Resource, Store, ...).
"""

from fleet_async.core import *  # noqa: F403  # re-export the core's public API
from fleet_async.core import __all__ as _core_all
from fleet_async.tasks import *  # noqa: F403  # re-export the mission layer's public API
from fleet_async.tasks import __all__ as _tasks_all
from fleet_async.tasks.devices import device_resource, pass_through, ride

__version__ = "0.1.0"

__all__ = [
    *_core_all,
    *_tasks_all,
    "__version__",
    "device_resource",
    "pass_through",
    "ride",
]
