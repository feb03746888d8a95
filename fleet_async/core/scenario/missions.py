"""The ``missions:`` section of a scenario: which coroutines run the fleet, with which arguments.

Each entry names an async function as ``"module:function"`` and may give it arguments::

    missions:
      - warehouse_missions:shift                   # shift(sim)
      - function: ../warehouse_missions.py:shift   # a file, relative to the scenario file
        args: [6]                                  # shift(sim, 6, orders=12)
        kwargs: {orders: 12}
        name: day_shift                            # the mission's name (default: the function's)

The function is called as ``function(sim, *args, **kwargs)``. ``module`` is a module name,
found beside the scenario file first (``<folder>/module.py`` or a package folder), then on
``sys.path``; or a path to a ``.py`` file, relative to the scenario file. Entries are resolved
(imported and checked against the function's signature) when the scenario loads, so a typo is
an error naming the file, the entry and the value before anything runs.

The core only describes the missions (``sim.scenario_missions``); running them is
``fleet_async.run_scenario`` (or ``fleet-async run``), which starts each one as a mission.
"""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import inspect
import os
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

from fleet_async.core.scenario.errors import expect_type, reject_unknown_keys

__all__ = ["MISSION_KEYS", "MissionSpec", "parse_missions"]

MISSION_KEYS = ("function", "args", "kwargs", "name")
"""Keys of a ``missions:`` entry written as a mapping."""


@dataclasses.dataclass(frozen=True)
class MissionSpec:
    """One resolved ``missions:`` entry.

    Attributes:
        label: Where it was declared (``missions[0]``).
        target: The ``"module:function"`` text as written.
        function: The async function it names.
        args: Positional arguments after ``sim``.
        kwargs: Keyword arguments.
        name: The mission's name.
    """

    label: str
    target: str
    function: Callable[..., Any]
    args: tuple[Any, ...] = ()
    kwargs: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    name: str = ""

    def coroutine_function(self) -> Callable[[Any], Any]:
        """``f(sim)`` that calls the function with the entry's arguments (to start as a
        mission)."""
        function, args, kwargs = self.function, self.args, dict(self.kwargs)

        async def mission(sim: Any) -> Any:
            return await function(sim, *args, **kwargs)

        mission.__name__ = mission.__qualname__ = self.name
        return mission


def parse_missions(
    entries: Any, where: str, base_dir: str | os.PathLike[str] | None
) -> list[MissionSpec]:
    """Check and resolve every ``missions:`` entry.

    Args:
        entries: The section's value (a list).
        where: The file prefix for errors (``"scenario.yaml: "``).
        base_dir: The scenario file's folder, searched first for modules.

    Raises:
        ValueError: for a malformed entry, a module or function that cannot be found, a
            function that is not ``async def``, or arguments its signature does not take;
            naming the file, ``missions[i]`` and the value.
    """
    expect_type(entries, (list, tuple), "a list of 'module:function' entries", where, "missions")
    specs = [
        _parse_entry(entry, f"missions[{i}]", where, base_dir) for i, entry in enumerate(entries)
    ]
    names = [spec.name for spec in specs]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ValueError(
                f"{where}missions[{i}].name: mission name {name!r} is used twice; give each "
                "entry its own 'name:'"
            )
    return specs


def _parse_entry(
    entry: Any, label: str, where: str, base_dir: str | os.PathLike[str] | None
) -> MissionSpec:
    if isinstance(entry, str):
        entry = {"function": entry}
    expect_type(
        entry, dict, "'module:function' or a mapping {function, args, kwargs, name}", where, label
    )
    reject_unknown_keys(list(entry), MISSION_KEYS, where, label)
    if "function" not in entry:
        raise ValueError(f"{where}{label}: missing 'function: module:function'")
    target = expect_type(
        entry["function"], str, "a string 'module:function'", where, f"{label}.function"
    )
    args = entry.get("args")
    args = () if args is None else tuple(expect_type(args, list, "a list", where, f"{label}.args"))
    kwargs = entry.get("kwargs")
    kwargs = (
        {} if kwargs is None else expect_type(kwargs, dict, "a mapping", where, f"{label}.kwargs")
    )
    function = _resolve(target, f"{where}{label}.function", base_dir)
    name = entry.get("name", getattr(function, "__name__", target))
    expect_type(name, str, "a name (string)", where, f"{label}.name")
    try:
        inspect.signature(function).bind(None, *args, **kwargs)
    except TypeError as exc:
        raise ValueError(
            f"{where}{label}: {target} is called as {target.rpartition(':')[2]}(sim, *args, "
            f"**kwargs) with args={list(args)!r} and kwargs={kwargs!r}, which its signature "
            f"{inspect.signature(function)} does not take: {exc}"
        ) from None
    return MissionSpec(label, target, function, args, kwargs, name)


def _resolve(target: str, at: str, base_dir: str | os.PathLike[str] | None) -> Callable[..., Any]:
    module_part, sep, function_name = target.rpartition(":")
    if not (sep and module_part and function_name.isidentifier()):
        raise ValueError(
            f"{at}: expected 'module:function' (e.g. 'my_missions:patrol', or "
            f"'../my_missions.py:patrol' for a file), got {target!r}"
        )
    module = _import(module_part, at, Path(base_dir) if base_dir is not None else Path.cwd())
    function = getattr(module, function_name, None)
    if function is None:
        public = sorted(
            n
            for n, v in vars(module).items()
            if inspect.iscoroutinefunction(v) and not n.startswith("_")
        )
        raise ValueError(
            f"{at}: module {module.__name__!r} ({module.__file__}) has no function "
            f"{function_name!r}; its async functions: {', '.join(public) or 'none'}"
        )
    if not inspect.iscoroutinefunction(function):
        raise ValueError(
            f"{at}: {target} is not an async function (a mission is 'async def "
            f"{function_name}(sim, ...)'), got {function!r}"
        )
    return function


def _import(module: str, at: str, base_dir: Path) -> ModuleType:
    """``module`` from a file beside the scenario if there is one, else from ``sys.path``."""
    if module.endswith(".py"):
        file = (base_dir / module).resolve()
        if not file.is_file():
            raise ValueError(f"{at}: no mission file {module!r}: {file} does not exist")
        return _import_file(file.stem, file, at)
    if not all(part.isidentifier() for part in module.split(".")):
        raise ValueError(
            f"{at}: {module!r} is neither a module name (e.g. 'my_missions') nor a .py file"
        )
    first = base_dir.joinpath(*module.split("."))
    if "." not in module and first.with_suffix(".py").is_file():
        return _import_file(module, first.with_suffix(".py").resolve(), at)
    try:
        sys.path.insert(0, str(base_dir))  # a package beside the scenario, for dotted names
        try:
            return importlib.import_module(module)
        finally:
            sys.path.remove(str(base_dir))
    except ModuleNotFoundError as exc:
        raise ValueError(
            f"{at}: cannot find module {module!r} beside the scenario ({first}.py) or on the "
            f"Python path ({exc})"
        ) from exc
    except Exception as exc:
        raise ValueError(f"{at}: importing {module!r} failed: {type(exc).__name__}: {exc}") from exc


def _import_file(name: str, file: Path, at: str) -> ModuleType:
    """Import ``file`` as module ``name`` (reusing it if that very file is loaded already)."""
    loaded = sys.modules.get(name)
    loaded_file = getattr(loaded, "__file__", None)
    if loaded is not None and loaded_file and Path(loaded_file).resolve() == file:
        return loaded
    spec = importlib.util.spec_from_file_location(name, file)
    if spec is None or spec.loader is None:
        raise ValueError(f"{at}: cannot import {file} as a Python module")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # before running it: dataclasses and pickling look it up
    folder = str(file.parent)
    sys.path.insert(0, folder)  # so it can import its own neighbours
    try:
        spec.loader.exec_module(module)
    except Exception as exc:
        del sys.modules[name]
        raise ValueError(f"{at}: importing {file} failed: {type(exc).__name__}: {exc}") from exc
    finally:
        sys.path.remove(folder)
    return module
