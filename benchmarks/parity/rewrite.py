"""Port a pybullet_fleet script to fleet_async by rewriting its import statements.

Three rewrites:

* :func:`map_imports` -- what the harness runs: every ``pybullet_fleet[.<module>]`` import
  becomes a lookup through ``parity_shim`` (top-level fleet_async names for now), so a
  script can run before ``fleet_async.<module>`` facades exist. It also reports which seed
  module paths the script needed.
* :func:`literal_import_check` -- the promise a user is given: rename ``pybullet_fleet`` to
  ``fleet_async`` and change nothing else. It builds a small program that tries each of the
  script's import statements, so the harness can say which ones a plain rename breaks.
* :func:`plain_rename` -- that promise applied to the whole script, as a user's search and
  replace would: the harness runs the result as it is.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass, field

OLD = "pybullet_fleet"
NEW = "fleet_async"
PRELUDE = "import parity_shim as __parity_shim__\n"


@dataclass
class Ported:
    """A rewritten script and the seed module paths it imported from."""

    source: str
    seed_modules: list[str] = field(default_factory=list)


def _seed_module(dotted: str) -> str | None:
    """``pybullet_fleet.agent`` -> ``agent``; ``pybullet_fleet`` -> ``""``; others -> None."""
    if dotted == OLD:
        return ""
    if dotted.startswith(OLD + "."):
        return dotted[len(OLD) + 1 :]
    return None


def _replacement(node: ast.stmt) -> tuple[str, list[str]] | None:
    """The statement that replaces an import of pybullet_fleet, and the modules it named."""
    if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
        seed = _seed_module(node.module)
        if seed is None:
            return None
        if any(a.name == "*" for a in node.names):
            return f"globals().update(__parity_shim__.star({seed!r}))", [seed]
        targets = ", ".join(a.asname or a.name for a in node.names)
        names = ", ".join(repr(a.name) for a in node.names)
        return f"{targets}, = __parity_shim__.import_names({seed!r}, {names})", [seed]
    if isinstance(node, ast.Import):
        if not any(_seed_module(a.name) is not None for a in node.names):
            return None
        parts, seeds = [], []
        for alias in node.names:
            seed = _seed_module(alias.name)
            if seed is None:
                parts.append(
                    f"import {alias.name}" + (f" as {alias.asname}" if alias.asname else "")
                )
            elif alias.asname:
                parts.append(f"{alias.asname} = __parity_shim__.module({seed!r})")
                seeds.append(seed)
            else:  # `import pybullet_fleet.x` binds the package name
                parts.append(f"{OLD} = __parity_shim__.module('')")
                seeds.append(seed)
        return "; ".join(parts), seeds
    return None


def _imports(tree: ast.AST) -> list[ast.stmt]:
    return [n for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))]


def map_imports(source: str) -> Ported:
    """Rewrite every pybullet_fleet import of ``source`` through ``parity_shim``."""
    tree = ast.parse(source)
    lines = source.splitlines(keepends=True)
    seeds: list[str] = []
    edits = []
    for node in _imports(tree):
        rep = _replacement(node)
        if rep is None:
            continue
        text, used = rep
        seeds += [s for s in used if s not in seeds]
        edits.append((node.lineno - 1, node.end_lineno or node.lineno, node.col_offset, text))
    for start, end, col, text in sorted(edits, reverse=True):
        indent = lines[start][:col]
        tail = lines[end - 1]
        after = tail[len(tail.rstrip("\r\n")) :] or "\n"
        lines[start:end] = [indent + text + after]
    body = "".join(lines)
    return Ported(source=_insert_prelude(body, tree), seed_modules=sorted(seeds))


def _insert_prelude(body: str, tree: ast.Module) -> str:
    """Put the shim import after the docstring and any ``from __future__`` import."""
    insert_at = 0
    for node in tree.body:
        is_doc = isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
        is_future = isinstance(node, ast.ImportFrom) and node.module == "__future__"
        if (is_doc and insert_at == 0) or is_future:
            insert_at = node.end_lineno or node.lineno
        else:
            break
    lines = body.splitlines(keepends=True)
    return "".join(lines[:insert_at]) + PRELUDE + "".join(lines[insert_at:])


def literal_import_check(source: str) -> str:
    """A program that tries each pybullet_fleet import with the package renamed, and prints
    one line per import: ``OK <stmt>`` or ``FAIL <stmt> -> <error>``."""
    tree = ast.parse(source)
    stmts = []
    for node in _imports(tree):
        if _replacement(node) is None:
            continue
        renamed = ast.unparse(node).replace(OLD, NEW)
        if renamed not in stmts:
            stmts.append(renamed)
    out = ["import sys"]
    for stmt in stmts:
        out += [
            "try:",
            f"    {stmt}",
            f"    print('OK', {stmt!r})",
            "except Exception as exc:",
            f"    print('FAIL', {stmt!r}, '->', type(exc).__name__ + ': ' + str(exc))",
        ]
    return "\n".join(out) + "\n"


def plain_rename(source: str) -> str:
    """``source`` with every ``pybullet_fleet`` renamed ``fleet_async`` and nothing else."""
    return re.sub(rf"\b{OLD}\b", NEW, source)
