"""Link and joint names of a PyBullet body to their indices.

PyBullet quirk handled here: bodies made by one ``createMultiBody(batchPositions=...)`` exist
on the server, but the client cache only learns the last one, so ``getBodyInfo`` fails on the
others until ``syncBodyInfo`` runs; ``_body_info`` does it once, on demand (doing it at spawn
costs 0.8 s per 10,000 bodies).
"""

from __future__ import annotations

import logging
import numbers

import pybullet as p

__all__ = [
    "UnknownNameError",
    "joint_index",
    "link_index",
    "resolve_joint_index",
    "resolve_link_index",
]

logger = logging.getLogger(__name__)


class UnknownNameError(ValueError):
    """A link or joint name the body does not have (the message lists the names it has)."""


def resolve_link_index(body_id: int, link: int | str, physics_client_id: int = 0) -> int:
    """Resolve a link name (or index) to its index, as the reference API does.

    Returns -1 for ``"base_link"`` and for a name the body does not have; the latter is logged
    as a warning that lists the body's link names (a typo would otherwise quietly mean the
    base). :func:`link_index` raises instead.

    Raises:
        ValueError: If an index is outside ``[-1, numJoints)`` or there is no such body.
        TypeError: If ``link`` is neither an int nor a str.
    """
    try:
        return link_index(body_id, link, physics_client_id)
    except UnknownNameError as exc:
        logger.warning("resolve_link_index: %s; returning -1", exc)
        return -1


def resolve_joint_index(body_id: int, joint: int | str, physics_client_id: int = 0) -> int:
    """Resolve a joint name (or index) to its index, as the reference API does.

    Returns -1 for a name the body does not have, logged as a warning that lists the body's
    joint names. :func:`joint_index` raises instead.

    Raises:
        ValueError: If an index is outside ``[0, numJoints)`` or there is no such body.
        TypeError: If ``joint`` is neither an int nor a str.
    """
    try:
        return joint_index(body_id, joint, physics_client_id)
    except UnknownNameError as exc:
        logger.warning("resolve_joint_index: %s; returning -1", exc)
        return -1


def link_index(body_id: int, link: int | str, physics_client_id: int = 0) -> int:
    """Resolve a link name (or index) of a PyBullet body to its link index.

    The base is index -1. A name matches the base link's own name, then each joint's child
    link; ``"base_link"`` also means the base when no link of that name exists.

    Args:
        body_id: PyBullet body unique id.
        link: Link index (passed through after a range check) or link name.
        physics_client_id: PyBullet client the body lives in.

    Returns:
        The link index, -1 for the base.

    Raises:
        ValueError: If an index is outside ``[-1, numJoints)``, or the name is unknown
            (:class:`UnknownNameError`; the message lists the body's link names).
        TypeError: If ``link`` is neither an int nor a str.
    """
    if type(link) is int and link == -1:
        return -1  # the base, which every body has: no need to ask PyBullet's body list
    count, base = _body_info(body_id, physics_client_id)
    if not isinstance(link, str):
        return _checked_index(link, -1, count, "link", body_id)
    names = [base] + [
        p.getJointInfo(body_id, i, physicsClientId=physics_client_id)[12].decode("utf-8")
        for i in range(count)
    ]
    if link in names:
        return names.index(link) - 1
    if link == "base_link":
        return -1
    raise UnknownNameError(f"Body {body_id} has no link named {link!r}; known links: {names}")


def joint_index(body_id: int, joint: int | str, physics_client_id: int = 0) -> int:
    """Resolve a joint name (or index) of a PyBullet body to its joint index.

    Args:
        body_id: PyBullet body unique id.
        joint: Joint index (passed through after a range check) or joint name.
        physics_client_id: PyBullet client the body lives in.

    Returns:
        The joint index, in ``[0, numJoints)``.

    Raises:
        ValueError: If an index is outside ``[0, numJoints)``, or the name is unknown
            (:class:`UnknownNameError`; the message lists the body's joint names).
        TypeError: If ``joint`` is neither an int nor a str.
    """
    count, _ = _body_info(body_id, physics_client_id)
    if not isinstance(joint, str):
        return _checked_index(joint, 0, count, "joint", body_id)
    names = [
        p.getJointInfo(body_id, i, physicsClientId=physics_client_id)[1].decode("utf-8")
        for i in range(count)
    ]
    if joint in names:
        return names.index(joint)
    raise UnknownNameError(f"Body {body_id} has no joint named {joint!r}; known joints: {names}")


def _body_info(body_id: int, client: int) -> tuple[int, str]:
    """Return the body's joint count and base link name; ValueError if there is no such body."""
    p.getNumJoints(body_id, physicsClientId=client)  # raises if not connected
    try:
        info = p.getBodyInfo(body_id, physicsClientId=client)
    except p.error:
        # Bodies made by one createMultiBody(batchPositions=...) call exist on PyBullet's
        # server, but its client-side cache only learns of the last one; refresh it once.
        p.syncBodyInfo(physicsClientId=client)
        try:
            info = p.getBodyInfo(body_id, physicsClientId=client)
        except p.error as exc:
            raise ValueError(f"No body with id {body_id} in physics client {client}") from exc
    # Read after the body list is current: a body it did not know reports no joints.
    count = p.getNumJoints(body_id, physicsClientId=client)
    return count, info[0].decode("utf-8")


def _checked_index(index: object, low: int, count: int, kind: str, body_id: int) -> int:
    if isinstance(index, bool) or not isinstance(index, numbers.Integral):
        raise TypeError(f"{kind}: expected an int index or a name, got {index!r}")
    value = int(index)
    if not low <= value < count:
        raise ValueError(
            f"{kind} index {value} out of range [{low}, {count}) for body {body_id} "
            f"with {count} joints"
        )
    return value
