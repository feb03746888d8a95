"""Architecture rules that must stay true."""

from __future__ import annotations

import ast
from pathlib import Path

import fleet_async

PACKAGE = Path(fleet_async.__file__).resolve().parent


def imports_of(folder: str, *prefixes: str) -> list[str]:
    """``file: module`` for every import under ``folder`` of a module starting with a prefix."""
    offenders = []
    for path in (PACKAGE / folder).rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [("." * node.level) + (node.module or "")]
            offenders += [f"{path.name}: {n}" for n in names if n.startswith(prefixes)]
    return offenders


def test_core_never_imports_tasks():
    assert imports_of("core", "fleet_async.tasks", "..tasks") == []


def test_core_and_tasks_never_import_the_sweep_or_the_cli():
    # Sweeps sit on top: they run simulations and missions; nothing below knows about them.
    above = ("fleet_async.sweep", "fleet_async.cli", "..sweep", "..cli")
    assert imports_of("core", *above) == []
    assert imports_of("tasks", *above) == []


def test_only_the_cli_and_examples_reach_the_fleet_interfaces():
    # Fleet interfaces stand beside missions and trees, above the core: the core and the
    # mission layer drive robots without knowing a master may.
    for folder in ("core", "tasks", "behavior", "sweep", "viewer"):
        assert imports_of(folder, "fleet_async.interfaces", "..interfaces") == [], folder


def test_the_package_imports_no_vda5050_package():
    # VDA 5050 is translated in fleet_async/interfaces/vda5050/ from the standard's schemas;
    # third-party VDA 5050 packages (vda5050-sdk's `vda5050`) are for the tests only.
    assert imports_of(".", "vda5050") == []


def test_public_names_are_exported_and_resolve():
    for name in fleet_async.__all__:
        assert hasattr(fleet_async, name), name


def test_core_names_are_exported_by_the_package():
    import fleet_async.core as core

    for name in core.__all__:
        assert getattr(core, name) is getattr(fleet_async, name), name
