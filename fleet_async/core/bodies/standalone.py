"""What a SimObject made without a simulation holds until ``sim.add_object`` adopts it.

The reference API allows ``SimObject(body_id, sim_core=None)``: such an object keeps its own
pose (a private one-row state store, written through to PyBullet's default client 0) and can
carry and drop other objects, ``attach_object`` / ``detach_object`` returning True / False as
documented. Carried objects follow when their parent's pose is set.

When one end of an attachment joins a simulation, the attachment is kept by the end that is
still outside; when the other end joins the same simulation, the simulation takes it over (the
child then follows its parent every step). Until then the two move independently.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pybullet as p

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.world.links import UnknownNameError, link_index
from fleet_async.core.world.state import KinematicState

if TYPE_CHECKING:
    from fleet_async.core.bodies.sim_object import SimObject

__all__ = ["StandaloneLink", "StandaloneState", "read_standalone_mass"]

logger = logging.getLogger(__name__)

CLIENT = 0
"""PyBullet client of objects outside a simulation (the default one, as in the reference API)."""


@dataclass(eq=False)
class StandaloneLink:
    """``child`` fixed at ``relative`` in the frame of ``parent``'s link ``link_index``."""

    parent: SimObject
    child: SimObject
    link_index: int
    relative: Pose


def read_standalone_mass(body_id: int) -> float:
    """Total mass (kg) of every link of a body in client 0; 0.0 if it cannot be read."""
    if body_id < 0:
        return 0.0
    try:
        links = range(-1, p.getNumJoints(body_id, physicsClientId=CLIENT))
        return float(sum(p.getDynamicsInfo(body_id, i, physicsClientId=CLIENT)[0] for i in links))
    except p.error:
        return 0.0


class StandaloneState:
    """The pose and attachments of one object outside any simulation.

    Args:
        owner: The object.
        collision_code: Its collision mode's code in the state store.
        pose: (position, orientation) to start from; None reads the body from client 0.
    """

    def __init__(
        self,
        owner: SimObject,
        collision_code: int,
        pose: tuple[Sequence[float], Sequence[float]] | None = None,
    ) -> None:
        self.owner = owner
        self.store = KinematicState(1)
        position, orientation = pose if pose is not None else self._read_pose(owner.body_id)
        self.row = self.store.allocate(
            -1, owner.body_id, position, orientation, collision_code=collision_code
        )
        self.pose_written = False
        """Whether the pose was set while standalone (``add_object`` then keeps it)."""
        self.links: list[StandaloneLink] = []

    @staticmethod
    def _read_pose(body_id: int) -> tuple[Sequence[float], Sequence[float]]:
        try:
            if body_id >= 0:
                return p.getBasePositionAndOrientation(body_id, physicsClientId=CLIENT)
        except p.error:
            pass
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)

    # ----- queries ------------------------------------------------------------------------

    def children(self) -> list[SimObject]:
        """Objects this one carries, in attachment order."""
        return [link.child for link in self.links if link.parent is self.owner]

    def parent(self) -> SimObject | None:
        """The object carrying this one, or None."""
        return next((link.parent for link in self.links if link.child is self.owner), None)

    # ----- pose ---------------------------------------------------------------------------

    def write_pose(self, position: np.ndarray, orientation: np.ndarray) -> None:
        """Set the pose (store and PyBullet client 0); carried objects follow."""
        store, row = self.store, self.row
        store.position[row] = position
        store.orientation[row] = orientation
        store.mark_moved(row)
        store.dirty[row] = False
        self.pose_written = True
        body = self.owner.body_id
        # No body of that id in client 0: the object's own pose is the truth all the same.
        with contextlib.suppress(p.error):
            if body >= 0:
                p.resetBasePositionAndOrientation(
                    body, position.tolist(), orientation.tolist(), physicsClientId=CLIENT
                )
        for link in [lk for lk in self.links if lk.parent is self.owner]:
            self._place(link)

    def _frame(self, link_index: int) -> Pose:
        store, row = self.store, self.row
        base = Pose.from_arrays_unchecked(store.position[row].copy(), store.orientation[row].copy())
        if link_index == -1:
            return base
        state = p.getLinkState(
            self.owner.body_id, link_index, computeForwardKinematics=1, physicsClientId=CLIENT
        )
        return Pose(list(state[4]), list(state[5]))

    def _place(self, link: StandaloneLink) -> None:
        pose = self._frame(link.link_index).compose(link.relative)
        link.child.set_pose(pose, preserve_velocity=False)

    # ----- attach / detach ------------------------------------------------------------------

    def attach(
        self,
        child: SimObject,
        link: int | str,
        relative_pose: Pose | None,
        keep_world_pose: bool,
    ) -> bool:
        """Attach ``child`` (an object outside a simulation too); see ``attach_object``.

        Returns:
            True once attached; False (with a warning) for a link name the body lacks.

        Raises:
            ValueError: for the misuses ``attach_object`` documents.
        """
        parent = self.owner
        if child is parent:
            raise ValueError(f"attach_object: cannot attach {parent!r} to itself")
        held = child.get_attached_parent()
        if held is not None:
            where = "this object" if held is parent else repr(held)
            logger.warning(
                "attach_object: %r is already attached to %s; not attached (detach it first)",
                child,
                where,
            )
            return False
        ancestor: SimObject | None = parent
        while ancestor is not None:
            if ancestor is child:
                raise ValueError(
                    f"attach_object: {child!r} carries {parent!r}; attaching would make a cycle"
                )
            ancestor = ancestor.get_attached_parent()
        if relative_pose is not None and keep_world_pose:
            raise ValueError(
                "attach_object: give either relative_pose or keep_world_pose=True, not both"
            )
        try:
            index = link_index(parent.body_id, link, CLIENT) if parent.body_id >= 0 else -1
        except UnknownNameError as exc:
            logger.warning("attach_object: %s; %r not attached", exc, child)
            return False
        if keep_world_pose:
            relative = self._frame(index).inverse().compose(child.get_pose())
        else:
            relative = relative_pose if relative_pose is not None else Pose([0.0, 0.0, 0.0])
        record = StandaloneLink(parent, child, index, relative)
        self.links.append(record)
        other = child.standalone_state
        if other is not None:
            other.links.append(record)
        self._place(record)
        return True

    def detach(
        self, child: SimObject, drop_pose: Pose | None, drop_relative_pose: Pose | None
    ) -> bool:
        """Detach ``child``; see ``detach_object``. False (with a warning) if not carried."""
        if drop_pose is not None and drop_relative_pose is not None:
            raise ValueError("detach_object: give either drop_pose or drop_relative_pose, not both")
        record = next(
            (lk for lk in self.links if lk.parent is self.owner and lk.child is child), None
        )
        if record is None:
            logger.warning(
                "detach_object: %r is not attached to %r; nothing detached", child, self.owner
            )
            return False
        self.forget(record)
        if drop_pose is not None:
            child.set_pose(drop_pose, preserve_velocity=False)
        elif drop_relative_pose is not None:
            child.set_pose(child.get_pose().compose(drop_relative_pose), preserve_velocity=False)
        return True

    def forget(self, record: StandaloneLink) -> None:
        """Drop an attachment record from both ends that hold it."""
        for end in (record.parent, record.child):
            state = end.standalone_state
            if state is not None and record in state.links:
                state.links.remove(record)
