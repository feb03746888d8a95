"""What the world needs of the objects it holds.

``World``, its attachments and its pending bodies keep the handles they are given and ask them
only these members: their ids and rows, their PyBullet body, their collision mode, whether
they are agents, update, have callbacks or an event bus, what they carried outside a
simulation, and ``bind`` / ``unbind`` to a simulation. ``SimObject`` satisfies ``WorldBody``;
``World`` is generic over the handle class, so whoever builds it (the kernel builds a
``World[SimObject]``) gets its own class back from ``objects``, ``get`` and the attachments.
The world never looks inside the simulation it binds handles to: it keeps it as an opaque
owner (``object``), compared by identity and passed on in events. This floor imports neither.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

if TYPE_CHECKING:
    from fleet_async.core.base.events import EventBus
    from fleet_async.core.base.types import CollisionMode
    from fleet_async.core.geometry.pose import Pose
    from fleet_async.core.world.state import KinematicState

__all__ = ["AttachedBody", "KeptOutside", "PendingHandle", "WorldBody"]

_Self = TypeVar("_Self")


class PendingHandle(Protocol):
    """A handle whose body is created later, with others: it is told its body id then."""

    def bind_body(self, body_id: int) -> None: ...


class AttachedBody(Protocol):
    """An object in an attachment: its id, its row in the state store and its body."""

    @property
    def object_id(self) -> int: ...

    @property
    def state_row(self) -> int: ...

    @property
    def body_id(self) -> int: ...


class KeptOutside(Protocol):
    """What an object kept while in no simulation: whether its pose was written, and its
    attachments to other objects (records with ``parent``, ``child``, ``link_index`` and
    ``relative``; the world re-makes those whose other end is already in the simulation)."""

    @property
    def pose_written(self) -> bool: ...

    @property
    def links(self) -> Sequence[Any]: ...

    def forget(self, record: Any) -> None: ...


class WorldBody(AttachedBody, PendingHandle, Protocol):
    """An object, as the world that holds it sees it."""

    @property
    def sim_core(self) -> object | None: ...

    @property
    def raw_body_id(self) -> int: ...

    @property
    def server_body_id(self) -> int: ...

    @property
    def standalone_state(self) -> KeptOutside | None: ...

    @property
    def collision_mode(self) -> CollisionMode: ...

    @property
    def is_agent(self) -> bool: ...

    @property
    def spawned_event(self) -> str | None: ...

    @property
    def removed_event(self) -> str | None: ...

    @property
    def events(self) -> EventBus: ...

    def bind(self, sim: Any, store: KinematicState, row: int, object_id: int) -> None: ...

    def unbind(self) -> None: ...

    def on_removed(self) -> None: ...

    def overrides_update(self) -> bool: ...

    def has_callbacks(self) -> bool: ...

    def execute_callbacks(self, current_time: float) -> None: ...

    def callback_steps_until_due(self, step: int, timestep: float, limit: int) -> int: ...

    def has_event_bus(self) -> bool: ...

    def get_pose(self) -> Pose: ...

    def set_pose(self, pose: Pose, preserve_velocity: bool = True) -> bool: ...

    def get_attached_parent(self: _Self) -> _Self | None: ...

    def get_attached_objects(self: _Self) -> list[_Self]: ...
