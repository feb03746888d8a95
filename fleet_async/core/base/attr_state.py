"""Checkpoint state of user-extensible pieces (plugins, controllers): their attributes."""

from __future__ import annotations

from typing import Any

__all__ = ["AttributeState"]


class AttributeState:
    """``get_state`` / ``set_state`` for ``sim.save_state``: the object's attributes (objects
    of the simulation are saved by id). Override both methods if some attribute cannot be
    pickled or must not be restored."""

    def get_state(self) -> dict[str, Any]:
        """What ``sim.save_state`` keeps of this object: its attributes."""
        return dict(vars(self))

    def set_state(self, state: dict[str, Any]) -> None:
        """Take back what :meth:`get_state` returned (``sim.restore_state``)."""
        vars(self).update(state)
