"""Checkpoint state of user-extensible pieces (plugins, controllers): their attributes."""

from __future__ import annotations

from typing import Any

__all__ = ["AttributeState"]


class AttributeState:
    """``get_state`` / ``set_state`` for ``sim.save_state``: the object's attributes (objects
    of the simulation are saved by id, random streams by key). A checkpoint holds plain data only
    (numbers, strings, lists, dicts, numpy arrays): override both methods if some attribute is
    not (a function, a lock, an instance of your own class) or must not be restored."""

    def get_state(self) -> dict[str, Any]:
        """What ``sim.save_state`` keeps of this object: its attributes."""
        return dict(vars(self))

    def set_state(self, state: dict[str, Any]) -> None:
        """Take back what :meth:`get_state` returned (``sim.restore_state``)."""
        vars(self).update(state)
