"""The simulation's object registry methods (the reference API's names), on its World.

Mixed into the simulation kernel: the object lists, lookups, adding and removing objects, and
poses in bulk. The objects themselves live in ``world/world.py``.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from fleet_async.core.bodies.sim_object import SimObject
    from fleet_async.core.world.backend import PyBulletBackend
    from fleet_async.core.world.world import World

__all__ = ["ObjectsApi"]

logger = logging.getLogger(__name__)


class ObjectsApi:
    """Objects of a simulation (mixed into the simulation kernel)."""

    # Provided by the simulation kernel.
    _world: World[SimObject]
    _backend: PyBulletBackend
    _managers: list[Any]

    @property
    def sim_objects(self) -> list[SimObject]:
        """Every object, in spawn order."""
        return self._world.objects

    @property
    def objects(self) -> list[SimObject]:
        """Every object, in spawn order (the same list as :attr:`sim_objects`).

        The reference API's examples use both names (``[o for o in sim.objects if ...]``).
        """
        return self._world.objects

    @property
    def _sim_objects_dict(self) -> Mapping[int, SimObject]:
        """Read-only ``{object_id: object}`` view, kept for scripts ported from the reference API.

        Its documentation's own example reads ``sim_core._sim_objects_dict[obj_id]``, so the
        name is sanctioned here despite its underscore: a live view that cannot be written to.
        New code should call :meth:`get_object_by_id`.
        """
        return self._world.objects_by_id()

    @property
    def agents(self) -> list[SimObject]:
        """Every agent, in spawn order."""
        return self._world.agents

    def body_mass(self, body_id: int, link: int = -1) -> float:
        """Mass (kg) PyBullet holds for one link of ``body_id`` (-1: the base); 0.0 for no
        body (-1)."""
        return self._backend.body_mass(body_id, link) if body_id >= 0 else 0.0

    def body_total_mass(self, body_id: int) -> float:
        """Mass (kg) of every link of ``body_id`` summed (a URDF's total); 0.0 for no body."""
        return self._backend.body_total_mass(body_id) if body_id >= 0 else 0.0

    def get_object_by_id(self, object_id: int) -> SimObject | None:
        """The object with ``object_id``, or None."""
        return self._world.get(object_id)

    def add_object(self, obj: SimObject, notify: bool = True) -> None:
        """Register ``obj`` (``SimObject.__init__`` does this when given ``sim_core``).

        An object made without a simulation brings the pose it kept meanwhile (and what it
        carries) into the state store.

        Args:
            obj: The object.
            notify: Emit the spawn events now (else ``sim.world.announce(obj)`` does later).

        A second call for an object already in this simulation does nothing (as the reference
        implementation; logged at debug level).

        Raises:
            ValueError: if ``obj`` belongs to another simulation.
        """
        if obj.sim_core is self and self._world.get(obj.object_id) is obj:
            logger.debug("add_object: %r is already in this simulation; nothing to do", obj)
            return
        self._world.add(obj, notify)

    def remove_object(self, obj: SimObject) -> None:
        """Remove ``obj`` from the simulation, its managers and PyBullet.

        Objects it carried are detached where they are. Removing an object that was already
        removed does nothing (as the reference implementation; logged at debug level).

        Raises:
            ValueError: if ``obj`` is part of another simulation, or never was part of one.
        """
        if obj.sim_core is None and obj.is_removed:
            logger.debug("remove_object: %r was already removed; nothing to do", obj)
            return
        if self._world.get(obj.object_id) is not obj:
            raise ValueError(f"remove_object: {obj!r} is not part of this simulation")
        for manager in list(self._managers):
            manager.remove_object(obj)
        self._world.remove(obj)

    def set_poses(
        self,
        object_ids: Sequence[int],
        positions: np.ndarray,
        orientations: np.ndarray,
        *,
        preserve_velocity: bool = True,
    ) -> None:
        """Set the poses of N objects in one call (arrays of shape (N, 3) and (N, 4)).

        Raises:
            ValueError: on shape mismatch, non-finite values or a zero quaternion.
            KeyError: for an object id that is not registered.
        """
        self._world.set_poses(
            object_ids, positions, orientations, preserve_velocity=preserve_velocity
        )

    def get_poses(self, object_ids: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """Return (positions (N, 3), orientations (N, 4)) copies for N objects.

        Raises:
            KeyError: for an object id that is not registered.
        """
        return self._world.get_poses(object_ids)
