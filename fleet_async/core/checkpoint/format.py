"""The checkpoint file: a header, then the state, pickled with the simulation's objects by id.

The header (format name, version, timestep, every object's id and type) is a pickle of its own,
read first, so a restore can refuse a simulation built differently before it reads anything
that refers to objects. The state is pickled with the simulation and its objects as persistent
references (``("sim",)``, ``("object", id)``), resolved against the simulation restored into.
"""

from __future__ import annotations

import dataclasses
import pickle
from typing import IO, TYPE_CHECKING, Any

from fleet_async.core.bodies.sim_object import SimObject

if TYPE_CHECKING:
    from fleet_async.core.actions.action_queue import ActionQueue
    from fleet_async.core.base.scheduling import PeriodicSchedule
    from fleet_async.core.collision.system import CollisionSystem
    from fleet_async.core.motion.joints import JointMotion
    from fleet_async.core.motion.kinematics import KinematicEngine
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = [
    "FORMAT",
    "ROW_COLUMNS",
    "VERSION",
    "CheckpointError",
    "CheckpointParts",
    "StatePickler",
    "StateUnpickler",
    "type_name",
    "typed_states",
]

FORMAT = "fleet_async checkpoint"
VERSION = 1
ROW_COLUMNS = ("position", "orientation", "velocity", "angular_velocity", "moved")
"""Columns of the state store saved for every object's row."""


class CheckpointError(ValueError):
    """A simulation that cannot be saved, or a checkpoint that cannot be restored into it."""


@dataclasses.dataclass(frozen=True)
class CheckpointParts:
    """What the simulation hands the checkpoint: its clock and its collaborators."""

    step_count: int
    collision_count: int
    paused: bool
    engine: KinematicEngine
    actions: ActionQueue
    callbacks: PeriodicSchedule
    plugin_schedule: PeriodicSchedule
    collision: CollisionSystem
    joint_motion: JointMotion
    other_motion: tuple[object, ...] = ()
    """Motion systems added with ``sim.add_motion_system`` (the devices' one, say): a
    checkpoint does not capture them, so saving refuses while there are any."""


class StatePickler(pickle.Pickler):
    """Saves the simulation and its objects by reference (``("object", id)``)."""

    def __init__(self, file: IO[bytes], sim: SimulationKernel) -> None:
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self._sim = sim

    def persistent_id(self, obj: Any) -> Any:
        """``("sim",)`` for the simulation, ``("object", id)`` for its objects, else None.

        Raises:
            CheckpointError: for an object of another simulation.
        """
        if obj is self._sim:
            return ("sim",)
        if isinstance(obj, SimObject):
            if obj.sim_core is not self._sim:
                raise CheckpointError(f"save_state: the state refers to {obj!r}, not in it")
            return ("object", obj.object_id)
        return None


class StateUnpickler(pickle.Unpickler):
    """Reads what :class:`StatePickler` wrote, resolving references against ``sim``."""

    def __init__(self, file: IO[bytes], sim: SimulationKernel) -> None:
        super().__init__(file)
        self._sim = sim

    def persistent_load(self, pid: Any) -> Any:
        """The simulation or its object with the saved id.

        Raises:
            CheckpointError: for an object id this simulation does not have.
        """
        if pid == ("sim",):
            return self._sim
        obj = self._sim.get_object_by_id(pid[1])
        if obj is None:
            raise CheckpointError(f"restore_state: the checkpoint refers to object {pid[1]}")
        return obj


def type_name(obj: object) -> str:
    """``module.QualName`` of ``obj``'s type (how the header and typed states name types)."""
    return f"{type(obj).__module__}.{type(obj).__qualname__}"


def typed_states(items: list[Any]) -> list[tuple[str, dict[str, Any]]]:
    """``(type name, item.get_state())`` for each controller or plugin, in order."""
    return [(type_name(item), item.get_state()) for item in items]
