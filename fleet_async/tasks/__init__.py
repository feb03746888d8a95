"""Async missions on anyio: coroutines that drive the fleet in sim time.

``fleet_async.run(sim, main)`` runs ``main`` as a mission on asyncio or trio; missions await
``sim.sleep``, ``agent.move``, ``agent.pick``, ``sim.events.wait`` and friends, which park them
until the step loop gets there. The core never imports this package: it exposes the awaitables
and this runtime serves them.
"""

from fleet_async.tasks.errors import (
    ActionCancelledError,
    ActionFailedError,
    MissionDeadlockError,
    MissionError,
    MissionStalledError,
    NoMissionRuntimeError,
)
from fleet_async.tasks.run import run, run_async
from fleet_async.tasks.sync import Event, EventStream, Lock, Resource, Store

__all__ = [
    "ActionCancelledError",
    "ActionFailedError",
    "Event",
    "EventStream",
    "Lock",
    "MissionDeadlockError",
    "MissionError",
    "MissionStalledError",
    "NoMissionRuntimeError",
    "Resource",
    "Store",
    "run",
    "run_async",
]
