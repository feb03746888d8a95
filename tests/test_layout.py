"""Architecture rules that must stay true."""

from __future__ import annotations

import ast
from pathlib import Path

import fleet_async

PACKAGE = Path(fleet_async.__file__).resolve().parent


def test_core_never_imports_tasks():
    offenders = []
    for path in (PACKAGE / "core").rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [("." * node.level) + (node.module or "")]
            offenders += [
                f"{path.name}: {n}" for n in names if n.startswith(("fleet_async.tasks", "..tasks"))
            ]
    assert offenders == []


def test_public_names_are_exported_and_resolve():
    for name in fleet_async.__all__:
        assert hasattr(fleet_async, name), name


def test_core_names_are_exported_by_the_package():
    import fleet_async.core as core

    for name in core.__all__:
        assert getattr(core, name) is getattr(fleet_async, name), name
