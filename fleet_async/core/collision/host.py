"""What the collision system needs of the simulation that hosts it, and of its objects.

``CollisionSystem`` is handed the simulation, but reads only these members of it: the
settings, the world and its state store, the PyBullet client, object lookup, the event bus,
the highlight colour and the contact counter. ``MultiRobotSimulationCore`` satisfies
``CollisionHost`` and ``SimObject`` satisfies ``CollidingBody``; this floor imports neither.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from fleet_async.core.base.events import EventBus
    from fleet_async.core.base.params import SimulationParams
    from fleet_async.core.world.state import KinematicState
    from fleet_async.core.world.world import World

__all__ = ["CollidingBody", "CollisionHost"]


class CollidingBody(Protocol):
    """An object in a contact: its PyBullet body (to recolour it) and its own event bus."""

    @property
    def body_id(self) -> int: ...

    @property
    def events(self) -> EventBus: ...

    def has_event_bus(self) -> bool: ...


class CollisionHost(Protocol):
    """The simulation, as the collision system sees it."""

    collision_color: list[float]
    """RGBA for colliding objects when ``params.enable_collision_color_change`` is on."""

    @property
    def params(self) -> SimulationParams: ...

    @property
    def world(self) -> World: ...

    @property
    def state(self) -> KinematicState: ...

    @property
    def client(self) -> int: ...

    @property
    def events(self) -> EventBus: ...

    def get_object_by_id(self, object_id: int) -> CollidingBody | None: ...

    def note_collisions(self, started: int) -> None: ...
