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


def test_public_names_are_exported_and_resolve():
    for name in fleet_async.__all__:
        assert hasattr(fleet_async, name), name


def test_core_names_are_exported_by_the_package():
    import fleet_async.core as core

    for name in core.__all__:
        assert getattr(core, name) is getattr(fleet_async, name), name
