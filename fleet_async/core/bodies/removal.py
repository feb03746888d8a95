"""What is left of an object after it leaves its simulation: errors that name it.

``SimObject.unbind`` swaps the object's state store for a :class:`RemovedState`, so every read
or write of its pose, velocity or flags raises :class:`ObjectRemovedError` with a message that
names the object and says when it left, instead of returning a stale pose.
"""

from __future__ import annotations

from typing import Any, NoReturn

__all__ = ["ObjectRemovedError", "RemovedState", "removed_message"]


class ObjectRemovedError(RuntimeError):
    """An object that left its simulation (``sim.remove_object``, ``reset``) was used.

    The message names the object and says when it left; the object has no pose or state any
    more, so reading, moving or commanding it cannot mean anything.
    """


class RemovedState:
    """Stands in for the state store of an object that left its simulation: any use raises."""

    def __init__(self, message: str) -> None:
        self._message = message

    def __getattr__(self, name: str) -> NoReturn:
        raise ObjectRemovedError(self._message)


def removed_message(obj: Any, sim: Any) -> str:
    """The message of every error about ``obj`` once it left ``sim`` (now)."""
    when = f" at sim time {sim.sim_time:.3f} s" if sim is not None else ""
    return (
        f"{obj!r} was removed from its simulation{when} (sim.remove_object or sim.reset), so "
        "it has no pose or state any more; use the objects still in sim.sim_objects, or spawn "
        "a new one"
    )
