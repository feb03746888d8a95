"""Deadlock suspicion: robots stopped by each other's safety fields for too long.

Each step the safety fields hand over who holds whom: robot ``a`` is *held by* robot ``b``
when ``b`` stands in ``a``'s protective field and ``b`` is stopped too. A *blocked set* is what
is left of the stopped robots after repeatedly dropping every robot held by no robot left (a
robot waiting for a robot that will drive on is not blocked): every member is held by another
member, so none of them can move until something outside the set intervenes. Each connected
part of it that has stayed the same for ``deadlock_after`` seconds is reported once, as a
``deadlock_suspected`` event naming its members. Resolving it is the fleet's traffic control's
job.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

__all__ = ["DeadlockWatch", "blocked_sets"]


def blocked_sets(held_by: dict[int, set[int]]) -> list[frozenset[int]]:
    """The blocked sets of a held-by graph, as connected parts, each sorted by its minimum.

    Args:
        held_by: ``{robot: robots standing in its protective field that are stopped too}``
            for every stopped robot (keys and members are any hashable ids, here row ids).

    Returns:
        The connected parts (edges taken both ways) of the largest subset in which every
        member is held by another member.
    """
    members = {a for a, bs in held_by.items() if bs}
    changed = True
    while changed:
        changed = False
        for a in sorted(members):
            if not (held_by[a] & members) - {a}:
                members.discard(a)
                changed = True
    parts: list[frozenset[int]] = []
    seen: set[int] = set()
    undirected: dict[int, set[int]] = {a: set() for a in members}
    for a in members:
        for b in held_by[a] & members:
            if b != a:
                undirected[a].add(b)
                undirected[b].add(a)
    for start in sorted(members):
        if start in seen:
            continue
        part, todo = {start}, [start]
        while todo:
            for b in undirected[todo.pop()]:
                if b not in part:
                    part.add(b)
                    todo.append(b)
        seen |= part
        parts.append(frozenset(part))
    return parts


class DeadlockWatch:
    """Tracks blocked sets over steps and says which have lasted ``deadlock_after`` seconds.

    Args:
        deadlock_after: Seconds a blocked set must last before it is reported (> 0).
    """

    def __init__(self, deadlock_after: float = 10.0) -> None:
        self.deadlock_after = deadlock_after
        self._since: dict[frozenset[int], int] = {}  # blocked set -> step it was first seen
        self._reported: set[frozenset[int]] = set()
        self.count = 0
        """Blocked sets reported so far (``deadlock_suspected`` events)."""

    @property
    def deadlock_after(self) -> float:
        """Seconds a blocked set must last before it is reported."""
        return self._after

    @deadlock_after.setter
    def deadlock_after(self, value: float) -> None:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0
        if not ok:
            raise ValueError(f"deadlock_after: expected a number of seconds > 0, got {value!r}")
        self._after = float(value)

    @property
    def watching(self) -> bool:
        """Whether some blocked set is being timed (an update with no sets would change it)."""
        return bool(self._since or self._reported)

    def reset(self) -> None:
        """Forget every set and the count (simulation reset)."""
        self._since.clear()
        self._reported.clear()
        self.count = 0

    def get_state(self, key: Callable[[int], int]) -> dict[str, Any]:
        """Plain data for a checkpoint, members mapped through ``key`` (row -> object id)."""
        return {
            "after": self._after,
            "count": self.count,
            "since": [[sorted(map(key, s)), step] for s, step in self._since.items()],
            "reported": [sorted(map(key, s)) for s in self._reported],
        }

    def set_state(self, state: dict[str, Any], key: Callable[[int], int]) -> None:
        """Take a :meth:`get_state` back, members mapped through ``key`` (object id -> row)."""
        self.deadlock_after = state["after"]
        self.count = int(state["count"])
        self._since = {frozenset(map(key, s)): int(step) for s, step in state["since"]}
        self._reported = {frozenset(map(key, s)) for s in state["reported"]}

    def update(self, sets: Iterable[frozenset[int]], step: int, dt: float) -> list[frozenset[int]]:
        """Note the blocked sets of ``step``; return those reaching ``deadlock_after`` now."""
        current = set(sets)
        self._since = {s: self._since.get(s, step) for s in current}
        self._reported &= current
        due = []
        for s in sorted(current, key=min):
            if s not in self._reported and (step - self._since[s]) * dt >= self._after - 1e-9:
                self._reported.add(s)
                due.append(s)
        self.count += len(due)
        return due
