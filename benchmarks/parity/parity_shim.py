"""Where a ported script's ``pybullet_fleet.<module>`` names come from in fleet_async, for now.

The harness rewrites ``from pybullet_fleet.agent import Agent`` into
``Agent, = parity_shim.import_names("agent", "Agent")``. A name is looked up, in order:

1. in ``fleet_async.<module>`` if that module exists (the seed-module facades, once they land);
2. among fleet_async's top-level public names;
3. anywhere inside the fleet_async package (the name exists but is not public). The lookup
   walks the package rather than naming a path, so it survives the layout changing, and it is
   logged in :data:`NOTES` so the trace shows that a user could not have imported it.

Only ever imported by rewritten scripts running on fleet_async.
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import types
from typing import Any

import fleet_async

NOTES: list[dict[str, str]] = []
_SKIP = ("fleet_async.cli", "fleet_async.tasks")
_MISSING = object()


def _facade(seed_module: str) -> types.ModuleType | None:
    name = f"fleet_async.{seed_module}"
    try:
        if importlib.util.find_spec(name) is None:
            return None
    except ModuleNotFoundError:
        return None
    return importlib.import_module(name)


def _search(name: str, seed_module: str) -> tuple[str, Any]:
    """Find where ``name`` is defined in fleet_async.

    A definition in a module named like the seed module wins; otherwise the definition must be
    the only one in the package, so that a generic name (``main``) is not mapped to an
    unrelated function.
    """
    defined: list[tuple[str, Any]] = []
    for info in pkgutil.walk_packages(fleet_async.__path__, "fleet_async."):
        if info.name.startswith(_SKIP):
            continue
        try:
            module = importlib.import_module(info.name)
        except Exception:  # a module that cannot import headless is simply not a candidate
            continue
        value = getattr(module, name, _MISSING)
        if value is not _MISSING and getattr(value, "__module__", info.name) == info.name:
            defined.append((info.name, value))
    same_name = [d for d in defined if d[0].rsplit(".", 1)[-1] == seed_module]
    if len(same_name) == 1 or len(defined) == 1:
        return (same_name or defined)[0]
    where = ", ".join(d[0] for d in defined) or "nowhere"
    raise ImportError(
        f"cannot import name {name!r} (pybullet_fleet.{seed_module}) from fleet_async: "
        f"not public; defined in {where}"
    )


def resolve(seed_module: str, name: str) -> Any:
    """Return the fleet_async object a port of ``pybullet_fleet.<seed_module>.<name>`` gets."""
    facade = _facade(seed_module) if seed_module else None
    if facade is not None and hasattr(facade, name):
        return getattr(facade, name)
    if hasattr(fleet_async, name):
        value = getattr(fleet_async, name)
        if name in getattr(fleet_async, "__all__", ()) or not isinstance(value, types.ModuleType):
            return value
    where, value = _search(name, seed_module)
    note = {
        "name": name,
        "seed_module": f"pybullet_fleet.{seed_module}".rstrip("."),
        "found_in": where,
    }
    if note not in NOTES:
        NOTES.append(note)
    return value


def import_names(seed_module: str, *names: str) -> tuple[Any, ...]:
    """``from pybullet_fleet.<seed_module> import <names>`` on fleet_async."""
    return tuple(
        module(name) if _is_seed_submodule(seed_module, name) else resolve(seed_module, name)
        for name in names
    )


def _is_seed_submodule(seed_module: str, name: str) -> bool:
    return seed_module == "" and name in SEED_MODULES


class _SeedModule(types.ModuleType):
    """A stand-in for ``pybullet_fleet.<seed_module>`` whose attributes resolve lazily."""

    def __init__(self, seed_module: str) -> None:
        super().__init__(f"fleet_async[{seed_module}]")
        self._seed_module = seed_module

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        if _is_seed_submodule(self._seed_module, name):
            return module(name)
        return resolve(self._seed_module, name)


def module(seed_module: str) -> types.ModuleType:
    """``import pybullet_fleet.<seed_module> as m`` on fleet_async."""
    return _facade(seed_module) or _SeedModule(seed_module)


# The seed documents these modules; the incumbent has more (events, controller, ...), which
# scripts may import the same way.
SEED_MODULES = (
    "action",
    "agent",
    "agent_manager",
    "config_utils",
    "core_simulation",
    "data_monitor",
    "geometry",
    "logging_utils",
    "sim_object",
    "tools",
    "types",
    "events",
    "controller",
)


def star(seed_module: str) -> dict[str, Any]:
    """``from pybullet_fleet.<seed_module> import *`` on fleet_async."""
    facade = _facade(seed_module) if seed_module else None
    source = facade if facade is not None else fleet_async
    names = getattr(source, "__all__", [n for n in dir(source) if not n.startswith("_")])
    return {name: getattr(source, name) for name in names}
