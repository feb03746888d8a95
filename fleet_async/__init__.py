"""fleet_async: a kinematics-first multi-robot fleet simulator on PyBullet.

The public API mirrors pybullet_fleet's (``MultiRobotSimulationCore``, ``SimulationParams``,
``SimObject``, ``Pose``, ``Path``, ...). Everything listed in ``__all__`` is importable from
here; submodules live in ``fleet_async.core`` (the synchronous simulator) and
``fleet_async.tasks`` (async missions).
"""

from fleet_async.core import *  # noqa: F403  # re-export the core's public API
from fleet_async.core import __all__ as _core_all
from fleet_async.tasks import (
    ActionCancelledError,
    ActionFailedError,
    MissionDeadlockError,
    MissionError,
    MissionStalledError,
    run,
    run_async,
)

__version__ = "0.1.0"

__all__ = [
    *_core_all,
    "ActionCancelledError",
    "ActionFailedError",
    "MissionDeadlockError",
    "MissionError",
    "MissionStalledError",
    "__version__",
    "run",
    "run_async",
]
