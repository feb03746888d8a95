"""Parent/child attachments, and the pass that makes children follow their parents.

An attachment fixes a child at ``relative`` in the frame of one parent link. Children attached
to a base link (index -1) are updated in one vectorised pass per nesting depth, so a fleet
carrying a thousand pallets costs a few numpy operations per step, not a thousand PyBullet
calls. Children of a non-base link need the link's world pose, which only PyBullet's forward
kinematics knows; those go through ``link_pose`` one by one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Generic, TypeVar

import numpy as np

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.quaternions import (
    quat_multiply_batch,
    rotate_vectors_batch,
)
from fleet_async.core.world.state import KinematicState

if TYPE_CHECKING:
    from fleet_async.core.world.host import AttachedBody

__all__ = ["Attachment", "AttachmentSet"]

_B = TypeVar("_B", bound="AttachedBody")
"""The handle class of the objects attached (``SimObject`` in a simulation)."""

LinkPoseFn = Callable[[_B, int], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Attachment(Generic[_B]):
    """One child fixed to one parent link.

    Attributes:
        parent: The carrying object.
        child: The carried object.
        link_index: Parent link index; -1 is the base.
        relative: Child pose in the parent link's frame.
    """

    parent: _B
    child: _B
    link_index: int
    relative: Pose


class AttachmentSet(Generic[_B]):
    """Every attachment of one simulation, indexed by child and by parent.

    Args:
        store: The state store the objects' rows live in.
        link_pose: Returns (position, orientation) of ``(obj, link_index)`` in the world frame,
            for non-base links.
    """

    def __init__(self, store: KinematicState, link_pose: LinkPoseFn[_B]) -> None:
        self._store = store
        self._link_pose = link_pose
        self._by_child: dict[int, Attachment[_B]] = {}  # child object_id -> attachment
        self._children: dict[int, list[Attachment[_B]]] = {}  # parent object_id -> attachments
        self._plan: (
            list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[Attachment[_B]]]] | None
        ) = None
        # Per plan level: whether a pass has placed every child of it since the plan was built.
        self._seen: list[bool] = []
        # Per plan level, per child: whether it was composed, the parent orientation it was
        # last composed at, and the offset and orientation that compose gave. A parent whose
        # orientation kept its bits gives its children the same offset and orientation again.
        self._frames: list[tuple[np.ndarray, ...]] = []
        # One child placed on its own (attach, set_pose of a carrier): the parent-frame offset
        # and orientation by (parent orientation, relative pose), as compose_poses_batch gives
        # them for one row. A fleet's carried objects mostly share both, and the batch
        # functions cost far more than the arithmetic on one row.
        self._one: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}
        self.incremental = True
        """Recompute only the children whose parent or own row was written since the last pass
        (False: every child every step, the reference the incremental pass is tested
        against; both give the same bits)."""

    def __len__(self) -> int:
        return len(self._by_child)

    def add(self, attachment: Attachment[_B]) -> None:
        """Register an attachment (the caller has validated it)."""
        self._by_child[attachment.child.object_id] = attachment
        self._children.setdefault(attachment.parent.object_id, []).append(attachment)
        self._plan = None
        self._seen = []

    def remove(self, child: _B) -> Attachment[_B] | None:
        """Drop the attachment holding ``child``; return it, or None if it had none."""
        att = self._by_child.pop(child.object_id, None)
        if att is None:
            return None
        siblings = self._children[att.parent.object_id]
        siblings.remove(att)
        if not siblings:
            del self._children[att.parent.object_id]
        self._plan = None
        self._seen = []
        return att

    def clear(self) -> None:
        """Forget every attachment."""
        self._by_child.clear()
        self._children.clear()
        self._plan = None
        self._seen = []

    def of_child(self, child: _B) -> Attachment[_B] | None:
        """The attachment holding ``child``, if any."""
        return self._by_child.get(child.object_id)

    def children_of(self, parent: _B) -> list[_B]:
        """Objects attached to ``parent``, in attachment order."""
        return [a.child for a in self._children.get(parent.object_id, ())]

    def parent_ids(self) -> set[int]:
        """Object ids of everything that carries something."""
        return set(self._children)

    def descendants(self, parent: _B) -> list[_B]:
        """Everything ``parent`` carries, directly or nested, parents before children."""
        out: list[_B] = []
        for att in self._children.get(parent.object_id, ()):
            out.append(att.child)
            out.extend(self.descendants(att.child))
        return out

    def is_ancestor(self, candidate: _B, obj: _B) -> bool:
        """Whether ``candidate`` carries ``obj`` directly or through other attachments."""
        att = self._by_child.get(obj.object_id)
        while att is not None:
            if att.parent is candidate:
                return True
            att = self._by_child.get(att.parent.object_id)
        return False

    def place_child(self, att: Attachment[_B]) -> None:
        """Put one child where its attachment says, then its own children, recursively."""
        self.place_child_only(att)
        for grandchild in self._children.get(att.child.object_id, ()):
            self.place_child(grandchild)

    def follow_parent(self, parent: _B) -> None:
        """Move everything ``parent`` carries after the parent itself moved."""
        for att in self._children.get(parent.object_id, ()):
            self.place_child(att)

    def follow_all(self) -> None:
        """Make every child follow its parent, parents before children (once per step).

        A child whose parent and own row were not written since the last pass (the store's
        ``written`` flags, which every pose write sets) is where it belongs already, so only
        the others are composed: a flag gather per level instead of the quaternion arithmetic
        for every carried object. Composing a child again from unchanged poses gives the
        bits it has, so a written but unchanged row costs time, never a different result."""
        if not self._by_child:
            return
        if self._plan is None:
            self._plan = self._build_plan()
            self._seen = [False] * len(self._plan)
            self._frames = [
                (
                    np.zeros(len(c), bool),
                    np.zeros((len(c), 4)),
                    np.zeros((len(c), 3)),
                    np.zeros((len(c), 4)),
                )
                for _, c, _, _, _ in self._plan
            ]
        for level, (parent_rows, child_rows, rel_pos, rel_orn, link_atts) in enumerate(self._plan):
            if len(child_rows):
                self._follow_level(level, parent_rows, child_rows, rel_pos, rel_orn)
            for att in link_atts:
                self.place_child_only(att)
        store = self._store
        store.written[: store.high_water] = False

    def _follow_level(
        self,
        level: int,
        parent_rows: np.ndarray,
        child_rows: np.ndarray,
        rel_pos: np.ndarray,
        rel_orn: np.ndarray,
    ) -> None:
        store = self._store
        stale: np.ndarray | slice = slice(None)
        if not (self._seen[level] and self.incremental):
            self._seen[level] = True  # every child, this once
        else:
            written = store.written
            stale = np.flatnonzero(written[parent_rows] | written[child_rows])
            if not len(stale):
                return
            parent_rows, child_rows = parent_rows[stale], child_rows[stale]
            rel_pos, rel_orn = rel_pos[stale], rel_orn[stale]
        parent_pos, parent_orn = store.position[parent_rows], store.orientation[parent_rows]
        if not self.incremental:  # the reference: every child composed afresh
            # Gathered rows are C-contiguous copies: a subset composes to the full pass's bits.
            offset = rotate_vectors_batch(rel_pos, parent_orn)
            self._write(child_rows, parent_pos + offset, quat_multiply_batch(parent_orn, rel_orn))
            return
        # A child whose parent's orientation has the bits of its last compose gets the same
        # offset and orientation (compose_poses_batch works row by row: a row's bits do not
        # depend on the rows composed with it), added to where the parent is now; only the
        # others are composed.
        known, at_orn, offsets, orns = self._frames[level]
        same = known[stale] & np.all(
            parent_orn.view(np.uint64) == at_orn[stale].view(np.uint64), axis=1
        )
        if not same.all():
            fresh = np.flatnonzero(~same)
            at = fresh if isinstance(stale, slice) else stale[fresh]
            turned = parent_orn[fresh]
            known[at], at_orn[at] = True, turned
            offsets[at] = rotate_vectors_batch(rel_pos[fresh], turned)
            orns[at] = quat_multiply_batch(turned, rel_orn[fresh])
        pos, orn = parent_pos + offsets[stale], orns[stale]
        self._write(child_rows, pos, orn)

    def place_child_only(self, att: Attachment[_B]) -> None:
        """Place one child from its parent link without recursing (the plan orders depths)."""
        parent_pos, parent_orn = self._parent_frame(att)
        rel = att.relative
        key = parent_orn.tobytes() + rel.position.tobytes() + rel.orientation.tobytes()
        known = self._one.get(key)
        if known is None:
            if len(self._one) >= 1024:
                self._one.clear()
            # compose_poses_batch's own two products, for one row
            parent_quat = parent_orn[None, :]
            known = self._one[key] = (
                rotate_vectors_batch(rel.position[None, :], parent_quat),
                quat_multiply_batch(parent_quat, rel.orientation[None, :]),
            )
        offset, orn = known
        pos = (parent_pos[None, :] + offset)[0].tolist()
        store, row = self._store, att.child.state_row
        quat = orn[0].tolist()
        if store.position[row].tolist() != pos or store.orientation[row].tolist() != quat:
            store.position[row] = pos
            store.orientation[row] = quat
            store.mark_moved(row)

    def _parent_frame(self, att: Attachment[_B]) -> tuple[np.ndarray, np.ndarray]:
        if att.link_index == -1:
            row = att.parent.state_row
            return self._store.position[row], self._store.orientation[row]
        return self._link_pose(att.parent, att.link_index)

    def _write(self, rows: np.ndarray, pos: np.ndarray, orn: np.ndarray) -> None:
        store = self._store
        changed = np.any(store.position[rows] != pos, axis=1) | np.any(
            store.orientation[rows] != orn, axis=1
        )
        if changed.any():
            moved = rows[changed]
            store.position[moved] = pos[changed]
            store.orientation[moved] = orn[changed]
            store.mark_moved(moved)

    def _depth(self, att: Attachment[_B]) -> int:
        depth = 0
        cur = self._by_child.get(att.parent.object_id)
        while cur is not None:
            depth += 1
            cur = self._by_child.get(cur.parent.object_id)
        return depth

    def _build_plan(
        self,
    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[Attachment[_B]]]]:
        levels: dict[int, list[Attachment[_B]]] = {}
        # Sorted by child id so the pass order is the same in every run.
        for child_id in sorted(self._by_child):
            att = self._by_child[child_id]
            levels.setdefault(self._depth(att), []).append(att)
        plan = []
        for depth in sorted(levels):
            base = [a for a in levels[depth] if a.link_index == -1]
            links = [a for a in levels[depth] if a.link_index != -1]
            plan.append(
                (
                    np.array([a.parent.state_row for a in base], dtype=np.int64),
                    np.array([a.child.state_row for a in base], dtype=np.int64),
                    np.array([a.relative.position for a in base]).reshape(-1, 3),
                    np.array([a.relative.orientation for a in base]).reshape(-1, 4),
                    links,
                )
            )
        return plan
