"""Composite missions that core objects offer but the mission layer implements.

Some device commands are whole missions built from the mission layer's own primitives:
``await elevator.ride(robot, "L2")`` holds the lift as a sim-aware Resource, calls it, boards,
travels and alights. The core cannot import ``fleet_async.tasks``, so the device method looks
its implementation up here by name, and ``fleet_async.tasks.devices`` registers it when it is
imported: ``fleet_async.tasks`` imports it, so the hooks are there once the mission layer is
loaded (``fleet_async.run``, ``import fleet_async.tasks``, or the first public name taken from
``fleet_async``). A bare ``import fleet_async`` does not load it: the package binds its public
names lazily, so that the command line starts without PyBullet.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["mission_hook", "register_mission_hook"]

_HOOKS: dict[str, Callable[..., Any]] = {}


def register_mission_hook(name: str, implementation: Callable[..., Any]) -> None:
    """Make ``implementation`` the mission behind the core command ``name`` (e.g.
    ``"elevator.ride"``); a later registration replaces an earlier one.

    Raises:
        ValueError: for an empty name.
        TypeError: if ``implementation`` is not callable.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"register_mission_hook: expected a non-empty name, got {name!r}")
    if not callable(implementation):
        raise TypeError(f"register_mission_hook({name!r}): {implementation!r} is not callable")
    _HOOKS[name] = implementation


def mission_hook(name: str) -> Callable[..., Any]:
    """The implementation registered for ``name``.

    Raises:
        RuntimeError: if none is registered (the mission layer was not imported).
    """
    try:
        return _HOOKS[name]
    except KeyError:
        raise RuntimeError(
            f"{name} is a mission of the mission layer, which is not loaded: "
            "import fleet_async.tasks first (fleet_async.run does)"
        ) from None
