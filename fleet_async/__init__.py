"""fleet_async: a kinematics-first multi-robot fleet simulator on PyBullet.

The public API mirrors pybullet_fleet's (``MultiRobotSimulationCore``, ``SimulationParams``,
``SimObject``, ``Pose``, ``Path``, ...). Everything listed in ``__all__`` is importable from
here; submodules live in ``fleet_async.core`` (the synchronous simulator) and
``fleet_async.tasks`` (async missions, and their sim-aware Event, Resource, Store, ...), and
``fleet_async.scenario_runner`` (``run_scenario``: a scenario's missions and actions, to the end).

The public names are loaded on first use (PEP 562), not when ``fleet_async`` itself is
imported: ``import fleet_async.cli`` must not import PyBullet, so that the command line can
keep PyBullet's build banner (printed by its C code at import) off the terminal. The first
``fleet_async.X`` or ``from fleet_async import X`` loads those packages and binds all their
public names here at once.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # what the lazy loader below binds, spelled out for type checkers
    from fleet_async.core import *  # noqa: F403
    from fleet_async.scenario_runner import *  # noqa: F403
    from fleet_async.tasks import *  # noqa: F403

__version__ = "0.1.0"

_SOURCES = ("fleet_async.core", "fleet_async.tasks", "fleet_async.scenario_runner")
"""The packages whose ``__all__`` this package re-exports, in this order."""


def _load() -> list[str]:
    """Import the re-exported packages and bind their public names in this module."""
    names: list[str] = []
    for source in _SOURCES:
        module = importlib.import_module(source)
        for name in module.__all__:
            globals()[name] = getattr(module, name)
        names.extend(module.__all__)
    exported = [*names, "__version__"]
    globals()["__all__"] = exported
    return exported


def __getattr__(name: str) -> Any:
    if name.startswith("__") and name != "__all__":
        raise AttributeError(f"module 'fleet_async' has no attribute {name!r}")
    exported = _load()
    if name in globals():
        return globals()[name]
    raise AttributeError(
        f"module 'fleet_async' has no attribute {name!r} ({len(exported)} public names: "
        "see fleet_async.__all__)"
    )


def __dir__() -> list[str]:
    return sorted({*globals(), *_load()})
