"""``fleet-async examples``: list (the default), run or copy the examples.

The examples are written once, in the repository's top-level ``examples/`` folder. The build
maps that folder into the wheel as ``fleet_async/examples/`` (``pyproject.toml`` /
``setup.py``), so an installed fleet-async has them inside the package; a source checkout
(an editable install, or ``PYTHONPATH``) uses ``examples/`` beside the package. Python examples
(``*.py``) run as scripts, in this process, with the PyBullet output the command hides;
scenarios (``scenarios/*.yaml``) run through ``fleet-async run``.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import difflib
import runpy
import shutil
import sys
import textwrap
from pathlib import Path

import fleet_async
from fleet_async.cli import run as run_command
from fleet_async.cli.errors import CliError

__all__ = [
    "Example",
    "add_arguments",
    "copy_examples",
    "examples_dir",
    "execute",
    "find_example",
    "list_examples",
    "run_script",
    "scenario_description",
    "script_description",
]

USAGE = "fleet-async examples [-h] [--verbose] [--list | --run NAME [ARGS ...] | --copy DIR]"
_SKIPPED_PARTS = ("__pycache__",)
_SKIPPED_SUFFIXES = (".pyc",)


@dataclasses.dataclass(frozen=True)
class Example:
    """One runnable example.

    Attributes:
        name: File name without extension (``hello_fleet``).
        path: The file.
        kind: ``"script"`` (a Python example) or ``"scenario"`` (a YAML scenario).
        description: First docstring line (scripts) or leading comment line (scenarios).
    """

    name: str
    path: Path
    kind: str
    description: str


# ----- finding examples -----------------------------------------------------------------------


def examples_dir() -> Path:
    """Where the examples are: ``fleet_async/examples/`` in an installed package, else the
    source tree's ``examples/`` beside the ``fleet_async`` package.

    Raises:
        CliError: if neither exists, naming both paths.
    """
    package = Path(fleet_async.__file__).resolve().parent
    candidates = (package / "examples", package.parent / "examples")
    for root in candidates:
        if (root / "scenarios").is_dir():
            return root
    raise CliError(
        f"no examples found: looked in {candidates[0]} (an installed fleet-async) and "
        f"{candidates[1]} (a source checkout). Reinstall fleet-async from its "
        "source checkout (python -m pip install -e .) or from a wheel built there."
    )


def _first_paragraph(lines: list[str]) -> str:
    """The first run of non-blank lines, joined with single spaces (a whole sentence even
    when the author wrapped it)."""
    paragraph: list[str] = []
    for line in lines:
        text = line.strip()
        if text:
            paragraph.append(text)
        elif paragraph:
            break
    return " ".join(paragraph)


def script_description(path: Path) -> str:
    """The first paragraph of a Python file's module docstring ("" without one)."""
    try:
        docstring = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8")))
    except (OSError, SyntaxError, UnicodeDecodeError) as exc:
        return f"(cannot read: {exc})"
    return _first_paragraph(docstring.splitlines()) if docstring else ""


def scenario_description(path: Path) -> str:
    """The first paragraph of the comment block at the top of a YAML file ("" without one)."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        return f"(cannot read: {exc})"
    comments: list[str] = []
    for line in lines:
        text = line.strip()
        if not text.startswith("#"):
            if text or comments:
                break
            continue
        comments.append(text.lstrip("#"))
    return _first_paragraph(comments)


def list_examples(root: Path) -> list[Example]:
    """Every ``root/*.py`` script, then every ``root/scenarios/*.yaml`` scenario, by name."""
    scripts = [
        Example(path.stem, path, "script", script_description(path))
        for path in sorted(root.glob("*.py"))
    ]
    scenarios = [
        Example(path.stem, path, "scenario", scenario_description(path))
        for path in sorted((root / "scenarios").glob("*.yaml"))
    ]
    return scripts + scenarios


def find_example(root: Path, name: str) -> Example:
    """The example called ``name`` (with or without its ``.py`` / ``.yaml`` extension).

    Raises:
        CliError: for an unknown name (listing the known ones) or a name that is both a
            script and a scenario (asking for the extension).
    """
    examples = list_examples(root)
    matches = [e for e in examples if name in (e.name, e.path.name)]
    if len(matches) > 1:
        files = ", ".join(m.path.name for m in matches)
        raise CliError(f"example {name!r} is ambiguous ({files}); add the extension")
    if not matches:
        names = sorted({e.name for e in examples})
        close = difflib.get_close_matches(name, names, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise CliError(
            f"no example named {name!r} in {root}{hint}; examples: {', '.join(names) or 'none'}"
        )
    return matches[0]


# ----- the actions ----------------------------------------------------------------------------


def _print_list(root: Path) -> int:
    examples = list_examples(root)
    width = max((len(e.name) for e in examples), default=0) + 2
    columns = shutil.get_terminal_size((100, 24)).columns
    groups = (
        ("script", "Python examples (fleet-async examples --run NAME [ARGS ...]):"),
        ("scenario", "Scenarios (fleet-async examples --run NAME [fleet-async run options]):"),
    )
    for kind, title in groups:
        print(title)
        for example in (e for e in examples if e.kind == kind):
            # Whole descriptions, wrapped under themselves rather than cut at the first line.
            lines = textwrap.wrap(example.description, max(40, columns - width - 2)) or [""]
            print(f"  {example.name:<{width}}{lines[0]}")
            for line in lines[1:]:
                print(f"  {'':<{width}}{line}")
    print(f"(from {root})")
    return 0


def _run_example(root: Path, argv: list[str]) -> int:
    if not argv:
        raise CliError("examples --run: give the example's NAME (see: fleet-async examples)")
    example = find_example(root, argv[0])
    extra = argv[1:]
    if example.kind == "scenario":
        parser = argparse.ArgumentParser(
            prog=f"fleet-async examples --run {example.name}",
            description=f"Run the scenario {example.path} (options as fleet-async run).",
        )
        run_command.add_arguments(parser)
        return run_command.execute(parser.parse_args([str(example.path), *extra]))
    return run_script(example.path, extra)


def run_script(path: Path, argv: list[str]) -> int:
    """Run the Python file ``path`` as ``__main__`` in this process, as ``python path argv``
    would (its folder first on ``sys.path``); return its exit code."""
    saved_argv, saved_path = sys.argv, list(sys.path)
    sys.argv = [str(path), *argv]
    sys.path.insert(0, str(path.parent))
    try:
        runpy.run_path(str(path), run_name="__main__")
    except SystemExit as exc:
        return _exit_code(exc.code)
    except KeyboardInterrupt:
        return run_command.INTERRUPTED_EXIT_CODE
    finally:
        sys.argv = saved_argv
        sys.path[:] = saved_path
    return 0


def _exit_code(code: object) -> int:
    """The process exit code ``SystemExit(code)`` stands for."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code
    print(code, file=sys.stderr)
    return 1


def copy_examples(root: Path, destination: Path) -> list[Path]:
    """Copy every file under ``root`` into ``destination`` (created if missing), keeping the
    folder layout; caches (``__pycache__``, ``.pyc``) are left out.

    Returns:
        The files written.

    Raises:
        CliError: if any of the files already exists there (nothing is copied then), or
            ``destination`` is a file.
    """
    if destination.exists() and not destination.is_dir():
        raise CliError(f"examples --copy: {destination} exists and is not a folder")
    sources = [
        path
        for path in sorted(root.rglob("*"))
        if path.is_file()
        and not any(part in _SKIPPED_PARTS for part in path.relative_to(root).parts)
        and path.suffix not in _SKIPPED_SUFFIXES
    ]
    targets = [destination / path.relative_to(root) for path in sources]
    existing = [target for target in targets if target.exists()]
    if existing:
        shown = ", ".join(str(path) for path in existing[:3])
        more = f" and {len(existing) - 3} more" if len(existing) > 3 else ""
        raise CliError(
            f"examples --copy: not overwriting existing files: {shown}{more}; nothing was "
            "copied (choose a new or empty folder, or remove those files)"
        )
    for source, target in zip(sources, targets, strict=True):
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)
    return targets


# ----- the command ----------------------------------------------------------------------------


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``examples`` options to ``parser``."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument(
        "--list",
        action="store_true",
        help="list every example with a one-line description (what the command does without "
        "an option)",
    )
    group.add_argument(
        "--run",
        nargs=argparse.REMAINDER,
        metavar="NAME [ARGS ...]",
        help="NAME [ARGS ...]: run example NAME (with or without .py/.yaml); everything "
        "after NAME goes to the example: a script's own options (e.g. --max-steps 50), "
        "or fleet-async run's options for a scenario (e.g. --duration 30). Exits with the "
        "example's exit code",
    )
    group.add_argument(
        "--copy",
        metavar="DIR",
        type=Path,
        help="copy the examples folder's contents into DIR (created if missing), to edit "
        "them; refuses to overwrite any existing file",
    )


def execute(args: argparse.Namespace) -> int:
    """Run the ``examples`` command; return the exit code."""
    root = examples_dir()
    if args.run is not None:
        return _run_example(root, list(args.run))
    if args.copy is None:
        return _print_list(root)
    written = copy_examples(root, args.copy)
    print(f"copied {len(written)} files from {root} to {args.copy}")
    return 0
