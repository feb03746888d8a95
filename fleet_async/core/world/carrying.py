"""Carrying: attach and detach inside a simulation (mixed into World).

``SimObject.attach_object`` / ``detach_object`` land here for objects in a simulation; the
attachments themselves (following parents every step) are ``attachments.py``. Objects outside
any simulation carry each other through ``bodies/standalone.py``.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Generic, TypeVar

import numpy as np

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.world.attachments import Attachment, AttachmentSet
from fleet_async.core.world.links import UnknownNameError, link_index

if TYPE_CHECKING:
    from fleet_async.core.world.backend import PyBulletBackend
    from fleet_async.core.world.host import WorldBody
    from fleet_async.core.world.state import KinematicState

__all__ = ["Carrying"]

logger = logging.getLogger(__name__)

_B = TypeVar("_B", bound="WorldBody")
"""The handle class of the objects carried (``SimObject`` in a simulation)."""


class Carrying(Generic[_B]):
    """Attach / detach of objects in one simulation (mixed into World)."""

    # Provided by World.
    _sim: object
    _backend: PyBulletBackend
    _store: KinematicState
    _attachments: AttachmentSet[_B]
    _saved_mass: dict[int, float]
    _dynamic_rows: np.ndarray
    in_step: bool

    def link_pose(self, obj: _B, link_index: int) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError  # World's

    def attach(
        self,
        parent: _B,
        child: _B,
        link: int | str,
        relative_pose: Pose | None,
        keep_world_pose: bool,
    ) -> bool:
        """Attach ``child`` to ``parent``'s ``link``; see ``SimObject.attach_object``.

        Returns:
            True once attached; False, with a warning listing the parent's links, for a link
            name it does not have (the reference API's contract: "False otherwise").
        """
        if child is parent:
            raise ValueError(f"attach_object: cannot attach {parent!r} to itself")
        if child.sim_core is not self._sim:
            raise ValueError(
                f"attach_object: {child!r} is not part of the same simulation as {parent!r}"
            )
        held = self._attachments.of_child(child)
        if held is not None:
            where = "this object" if held.parent is parent else repr(held.parent)
            logger.warning(
                "attach_object: %r is already attached to %s; not attached (detach it first)",
                child,
                where,
            )
            return False
        if self._attachments.is_ancestor(child, parent):
            raise ValueError(
                f"attach_object: {child!r} carries {parent!r}; attaching would make a cycle"
            )
        if relative_pose is not None and keep_world_pose:
            raise ValueError(
                "attach_object: give either relative_pose or keep_world_pose=True, not both"
            )
        try:
            # The base needs no PyBullet body yet: a pending one stays pending.
            index = (
                link_index(parent.server_body_id, link, physics_client_id=self._backend.client)
                if parent.raw_body_id != -1 and not (type(link) is int and link == -1)
                else -1
            )
        except UnknownNameError as exc:
            logger.warning("attach_object: %s; %r not attached", exc, child)
            return False
        if keep_world_pose:
            link_pos, link_orn = (
                self.link_pose(parent, index)
                if index != -1
                else (
                    self._store.position[parent.state_row],
                    self._store.orientation[parent.state_row],
                )
            )
            relative = (
                Pose.from_arrays_unchecked(link_pos.copy(), link_orn.copy())
                .inverse()
                .compose(child.get_pose())
            )
        else:
            relative = relative_pose if relative_pose is not None else Pose([0.0, 0.0, 0.0])
        att = Attachment(parent, child, index, relative)
        self._attachments.add(att)
        row = child.state_row
        if not self._store.kinematic[row]:
            # A carried body is moved by its carrier, not by dynamics, until it is dropped.
            self._saved_mass[child.object_id] = self._backend.body_mass(child.server_body_id)
            self._backend.set_body_mass(child.server_body_id, 0.0)
            self._store.kinematic[row] = True
            self._dynamic_rows = self._dynamic_rows[self._dynamic_rows != row]
        self._attachments.place_child(att)
        if not self.in_step:
            self._backend.sync(self._store)
        return True

    def detach(
        self,
        parent: _B,
        child: _B,
        drop_pose: Pose | None,
        drop_relative_pose: Pose | None,
    ) -> bool:
        """Detach ``child`` from ``parent``; see ``SimObject.detach_object``."""
        if drop_pose is not None and drop_relative_pose is not None:
            raise ValueError("detach_object: give either drop_pose or drop_relative_pose, not both")
        att = self._attachments.of_child(child)
        if att is None or att.parent is not parent:
            logger.warning(
                "detach_object: %r is not attached to %r; nothing detached", child, parent
            )
            return False
        self._attachments.remove(child)
        mass = self._saved_mass.pop(child.object_id, None)
        if mass is not None:
            row = child.state_row
            self._backend.set_body_mass(child.server_body_id, mass)
            self._store.kinematic[row] = False
            self._dynamic_rows = np.append(self._dynamic_rows, row)
        if drop_pose is not None:
            child.set_pose(drop_pose, preserve_velocity=False)
        elif drop_relative_pose is not None:
            child.set_pose(child.get_pose().compose(drop_relative_pose), preserve_velocity=False)
        return True
