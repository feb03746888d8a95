"""Async missions: coroutines that drive the fleet in sim time.

``fleet_async.run(sim, main)`` runs ``main`` as a mission; missions await ``sim.sleep``,
``agent.move``, ``agent.pick``, ``sim.events.wait``, resources and stores, which park them until
the step loop gets there. A kernel of our own runs the missions (as SimPy runs its processes),
in one order on every anyio backend; the anyio host loop serves only their real-world awaits.
The core never imports this package: it exposes the awaitables and this runtime serves them.
"""

from fleet_async.tasks.conditions import AllOf, AnyOf
from fleet_async.tasks.devices import device_resource, pass_through, ride
from fleet_async.tasks.errors import (
    ActionCancelledError,
    ActionFailedError,
    Cancelled,
    ExternallyDrivenError,
    Interrupt,
    MissionCancelledError,
    MissionDeadlockError,
    MissionError,
    MissionStalledError,
    NoMissionRuntimeError,
)
from fleet_async.tasks.groups import TaskGroup
from fleet_async.tasks.kernel import SimEvent, Timeout
from fleet_async.tasks.missions import Mission
from fleet_async.tasks.resources import (
    Container,
    Lock,
    Preempted,
    PreemptiveResource,
    PriorityResource,
    Request,
    Resource,
)
from fleet_async.tasks.run import run, run_async
from fleet_async.tasks.scopes import CancelScope
from fleet_async.tasks.stores import FilterStore, PriorityItem, PriorityStore, Store
from fleet_async.tasks.sync import Event, EventStream
from fleet_async.tasks.waits import ActionWait

__all__ = [
    "ActionCancelledError",
    "ActionFailedError",
    "ActionWait",
    "AllOf",
    "AnyOf",
    "CancelScope",
    "Cancelled",
    "Container",
    "Event",
    "EventStream",
    "ExternallyDrivenError",
    "FilterStore",
    "Interrupt",
    "Lock",
    "Mission",
    "MissionCancelledError",
    "MissionDeadlockError",
    "MissionError",
    "MissionStalledError",
    "NoMissionRuntimeError",
    "Preempted",
    "PreemptiveResource",
    "PriorityItem",
    "PriorityResource",
    "PriorityStore",
    "Request",
    "Resource",
    "SimEvent",
    "Store",
    "TaskGroup",
    "Timeout",
    "device_resource",
    "pass_through",
    "ride",
    "run",
    "run_async",
]
