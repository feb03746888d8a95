"""What an object needs of the simulation it is in.

A ``SimObject`` keeps the simulation it joined (``sim_core``) and reads only these members of
it: the PyBullet client and whether it has a GUI, the settings (physics, model paths), the sim
time, the world and its attachments, the object list, adding and removing objects, the mass
PyBullet holds for a body, and batched spawning. ``SimulationKernel`` (so
``MultiRobotSimulationCore``) satisfies ``BodyHost``; this floor imports neither. Agents ask
more of it (``agents/host.py``).
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from fleet_async.core.base.params import SimulationParams
    from fleet_async.core.bodies.sim_object import SimObject
    from fleet_async.core.world.attachments import AttachmentSet
    from fleet_async.core.world.world import World

__all__ = ["BodyHost"]


class BodyHost(Protocol):
    """The simulation, as its objects see it."""

    @property
    def client(self) -> int: ...

    @property
    def is_gui(self) -> bool: ...

    @property
    def params(self) -> SimulationParams: ...

    @property
    def sim_time(self) -> float: ...

    @property
    def world(self) -> World[SimObject]: ...

    @property
    def attachments(self) -> AttachmentSet[SimObject]: ...

    @property
    def sim_objects(self) -> list[SimObject]: ...

    def add_object(self, obj: SimObject, notify: bool = True) -> None: ...

    def remove_object(self, obj: SimObject) -> None: ...

    def body_total_mass(self, body_id: int) -> float: ...

    def batch_spawn(self) -> AbstractContextManager[None]: ...
