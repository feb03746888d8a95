"""The layer contract of ``fleet_async.core`` (docs/architecture.md, "Layers").

Sub-packages of the core import only downward at run time: an import inside a function counts
as much as one at the top of a module. Imports under ``if TYPE_CHECKING:`` point downward too,
but for the pairs in ``TYPE_ONLY_UPWARD`` (none today): a lower floor annotates with a protocol
of its own (``world/host.py``, ``collision/host.py``, ``missions/host.py``, ...) that the class
above satisfies.
Sub-packages on one floor (``metrics`` and ``checkpoint``; ``scenario`` and ``view``) do not
import each other. Above the layers stand the public simulation class (``core/simulation.py``),
then ``fleet_async.core`` itself; the seed-module facades (``fleet_async.agent``, ...) stand
above everything, so nothing in the package imports them. ``fleet_async.tasks`` reaches the
core only through the mission seam, ``fleet_async.core.missions``.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

import fleet_async

PACKAGE = Path(fleet_async.__file__).resolve().parent
CORE = PACKAGE / "core"

LAYERS: tuple[tuple[str, ...], ...] = (
    ("base",),
    ("geometry",),
    ("world",),
    ("collision",),
    ("bodies",),
    ("motion",),
    ("actions",),
    ("routes",),  # route graphs and the action that follows them (under go_to_node)
    ("missions",),
    ("agents",),
    ("sim",),
    ("metrics", "checkpoint"),
    ("managers",),
    ("devices",),
    ("maps",),  # grid maps as static bodies (over bodies and the safety fields)
    ("scenario", "view"),
    ("simulation",),  # core/simulation.py: the public class, assembled from the layers
)
"""Floors of ``fleet_async.core``, bottom first; ``fleet_async.core`` itself stands above."""

FACADES = (
    "action",
    "agent",
    "agent_manager",
    "config_utils",
    "core_simulation",
    "data_monitor",
    "events",
    "geometry",
    "logging_utils",
    "sim_object",
    "tools",
    "types",
)
"""``fleet_async.<module>`` for each module of the reference API (seed-module facades)."""

TYPE_ONLY_UPWARD: frozenset[tuple[str, str]] = frozenset()
"""(module, imported module) pairs whose type-only import may point up a floor.

Empty: every floor annotates with protocols of its own (``*/host.py``). A pair belongs here only
where a floor must name a class above it in an annotation and a protocol of its own would not
do; a comment beside the pair says why, and a test fails once the import is gone, so the list
never outlives its reasons."""

MISSION_SEAM = "fleet_async.core.missions"
MAX_MODULES_PER_FOLDER = 15
MAX_LINES_PER_MODULE = 500

_FLOOR = {unit: floor for floor, units in enumerate(LAYERS) for unit in units}
_CORE_TOP = len(LAYERS)


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def is_module(name: str) -> bool:
    path = PACKAGE.parent.joinpath(*name.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _walk(node: ast.AST, type_only: bool) -> Iterator[tuple[ast.AST, bool]]:
    """Every node under ``node``, with whether it sits under ``if TYPE_CHECKING:``."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.If) and _is_type_checking(child.test):
            yield child.test, type_only
            for stmt in child.body:
                yield stmt, True
                yield from _walk(stmt, True)
            for stmt in child.orelse:
                yield stmt, type_only
                yield from _walk(stmt, type_only)
            continue
        yield child, type_only
        yield from _walk(child, type_only)


def imports(source: str, module: str, is_package: bool) -> Iterator[tuple[str, int, bool]]:
    """(imported fleet_async module, line, type_only) for every import in ``source``.

    ``from a.b import c`` names the module ``a.b.c`` when that is a module, else ``a.b``. A
    call ``importlib.import_module("fleet_async....")`` with a literal name counts too.
    """
    package = module if is_package else module.rpartition(".")[0]
    for node, type_only in _walk(ast.parse(source), False):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join([*anchor, *([base] if base else [])])
            for alias in node.names:
                full = f"{base}.{alias.name}"
                targets.append(full if is_module(full) else base)
        elif (
            isinstance(node, ast.Call)
            and getattr(node.func, "attr", getattr(node.func, "id", None))
            in ("import_module", "__import__")
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            targets = [node.args[0].value]
        for target in dict.fromkeys(targets):
            if target == "fleet_async" or target.startswith("fleet_async."):
                yield target, getattr(node, "lineno", 0), type_only


def floor_of(module: str) -> tuple[int, str] | None:
    """(floor, unit) of a core module; None outside the core."""
    parts = module.split(".")
    if parts[:2] != ["fleet_async", "core"]:
        return None
    if len(parts) == 2:
        return _CORE_TOP, "core"
    unit = parts[2]
    if unit not in _FLOOR:
        raise AssertionError(f"{module}: {unit!r} is on no floor of LAYERS")
    return _FLOOR[unit], unit


def upward_imports(
    source: str, module: str, is_package: bool = False, type_only_too: bool = False
) -> list[str]:
    """Imports of core module ``module`` that break the layer contract: run-time ones, and
    with ``type_only_too`` the type-only ones as well (but the pairs in ``TYPE_ONLY_UPWARD``)."""
    here = floor_of(module)
    assert here is not None, module
    bad = []
    for target, line, type_only in imports(source, module, is_package):
        if type_only and (not type_only_too or (module, target) in TYPE_ONLY_UPWARD):
            continue
        there = floor_of(target)
        if there is None:
            bad.append(f"{module}:{line} imports {target} (outside the core)")
        elif there[1] != here[1] and there[0] >= here[0]:
            kind = " for annotations" if type_only else ""
            bad.append(f"{module}:{line} imports {target}{kind} (floor {there[0]} >= {here[0]})")
    return bad


def package_modules(root: Path) -> Iterator[tuple[Path, str]]:
    for path in sorted(root.rglob("*.py")):
        yield path, module_name(path)


def test_core_imports_only_downward_at_run_time():
    bad = []
    for path, module in package_modules(CORE):
        bad += upward_imports(path.read_text(), module, path.name == "__init__.py")
    assert bad == []


def test_core_annotates_only_downward_but_for_the_justified_pairs():
    bad = []
    for path, module in package_modules(CORE):
        bad += upward_imports(path.read_text(), module, path.name == "__init__.py", True)
    assert bad == []


def test_the_justified_pairs_still_exist():
    found = set()
    for path, module in package_modules(CORE):
        for target, _, type_only in imports(path.read_text(), module, path.name == "__init__.py"):
            if type_only:
                found.add((module, target))
    assert sorted(TYPE_ONLY_UPWARD - found) == []


def test_every_core_module_stands_on_a_floor():
    for _path, module in package_modules(CORE):
        assert floor_of(module) is not None


def test_the_contract_sees_an_upward_import_inside_a_function():
    source = "def f():\n    from fleet_async.core.sim.kernel import SimulationKernel\n"
    assert upward_imports(source, "fleet_async.core.world.world") == [
        "fleet_async.core.world.world:2 imports fleet_async.core.sim.kernel (floor 10 >= 2)"
    ]


def test_the_contract_sees_a_type_only_upward_import():
    source = (
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n"
        "    from fleet_async.core.simulation import MultiRobotSimulationCore\n"
    )
    assert upward_imports(source, "fleet_async.core.geometry.pose") == []
    assert upward_imports(source, "fleet_async.core.geometry.pose", type_only_too=True) == [
        "fleet_async.core.geometry.pose:3 imports fleet_async.core.simulation for annotations"
        " (floor 16 >= 1)"
    ]


def test_floor_mates_do_not_import_each_other():
    source = "import fleet_async.core.view.gui\n"
    assert upward_imports(source, "fleet_async.core.scenario.build") == [
        "fleet_async.core.scenario.build:1 imports fleet_async.core.view.gui (floor 15 >= 15)"
    ]


def test_nothing_in_the_package_imports_a_facade():
    facades = {f"fleet_async.{name}" for name in FACADES}
    bad = []
    for path, module in package_modules(PACKAGE):
        if module in facades:
            continue
        for target, line, _ in imports(path.read_text(), module, path.name == "__init__.py"):
            if target in facades:
                bad.append(f"{module}:{line} imports {target}")
    assert bad == []


@pytest.mark.parametrize("name", FACADES)
def test_facades_import_only_the_core(name):
    path = PACKAGE / f"{name}.py"
    targets = [t for t, _, _ in imports(path.read_text(), f"fleet_async.{name}", False)]
    assert targets
    assert all(t.startswith("fleet_async.core") for t in targets), targets


def test_tasks_reach_the_core_only_through_the_mission_seam():
    bad = []
    for path, module in package_modules(PACKAGE / "tasks"):
        for target, line, _ in imports(path.read_text(), module, path.name == "__init__.py"):
            if target.startswith("fleet_async.core") and target != MISSION_SEAM:
                bad.append(f"{module}:{line} imports {target}")
    assert bad == []


def test_core_folders_stay_small():
    folders = [init.parent for init in CORE.rglob("__init__.py")]  # sub-packages' too
    for folder in folders:
        modules = [p for p in folder.glob("*.py") if p.name != "__init__.py"]
        assert len(modules) <= MAX_MODULES_PER_FOLDER, folder


def test_modules_of_the_whole_package_stay_small():
    for path in PACKAGE.rglob("*.py"):
        lines = len(path.read_text().splitlines())
        assert lines <= MAX_LINES_PER_MODULE, f"{path.relative_to(PACKAGE)}: {lines} lines"
