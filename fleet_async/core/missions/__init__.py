"""The mission seam: what the core offers to the async mission layer (``fleet_async.tasks``).

``fleet_async.tasks`` imports the core only from here (a test keeps it so). The seam is:

- ``MissionRuntime``: what a mission runtime must provide; ``fleet_async.run`` installs one
  with ``sim.set_mission_runtime``;
- ``SimMissionApi`` / ``SimEventBus`` (``mission_api.py``): the sim-time awaitables of the
  simulation (``sim.sleep``, ``sim.move_on_after``, ``sim.events.wait``, ...), which delegate
  to the installed runtime;
- ``AgentMissionApi`` (``agent_missions.py``): ``await agent.move(...)`` and the other agent
  commands, each queueing an Action and returning the runtime's event for it;
- what the runtime reads back: ``SimEvents``, ``ActionStatus``, ``Action``, ``MoveAction``,
  ``WaitAction``;
- what the mission layer uses of the objects above this floor, as protocols (``host.py``):
  ``MissionSim`` (the simulation ``fleet_async.run`` drives), ``MissionDoor`` and
  ``MissionElevator`` (what the device missions call); the classes above satisfy them;
- device composites (``hooks.py``): ``register_mission_hook`` lets ``fleet_async.tasks.devices``
  implement ``elevator.ride`` and ``door.pass_through``, which need the mission layer's own
  primitives; ``DeviceEvents`` names what devices emit;
- ``steps_for``: the package's one rule for sim seconds to whole steps (``core/base/steps.py``);
- ``frozen_heap``: the run's hold on the garbage collector's full collections
  (``core/base/memory.py``, ``SimulationParams.gc_freeze``).

May import ``actions`` and below, at run time and for annotations alike.
"""

from __future__ import annotations

from fleet_async.core.actions.action import Action, MoveAction, WaitAction
from fleet_async.core.base.device_events import DeviceEvents
from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.memory import frozen_heap
from fleet_async.core.base.steps import steps_for
from fleet_async.core.base.types import ActionStatus
from fleet_async.core.missions.agent_missions import AgentMissionApi
from fleet_async.core.missions.errors import (
    ExternallyDrivenError,
    MissionError,
    NoMissionRuntimeError,
)
from fleet_async.core.missions.hooks import mission_hook, register_mission_hook
from fleet_async.core.missions.host import MissionDevice, MissionDoor, MissionElevator, MissionSim
from fleet_async.core.missions.mission_api import MissionRuntime, SimEventBus, SimMissionApi

__all__ = [
    "Action",
    "ActionStatus",
    "AgentMissionApi",
    "DeviceEvents",
    "ExternallyDrivenError",
    "MissionDevice",
    "MissionDoor",
    "MissionElevator",
    "MissionError",
    "MissionRuntime",
    "MissionSim",
    "MoveAction",
    "NoMissionRuntimeError",
    "SimEventBus",
    "SimEvents",
    "SimMissionApi",
    "WaitAction",
    "frozen_heap",
    "mission_hook",
    "register_mission_hook",
    "steps_for",
]
