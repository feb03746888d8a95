"""Side-by-side check: the same seed-API scripts on fleet_async and on pybullet_fleet 0.8.0.

Usage::

    python benchmarks/parity/run.py                          # fleet_async only
    python benchmarks/parity/run.py --incumbent /tmp/pbf     # and diff against the incumbent
    python benchmarks/parity/run.py --incumbent /tmp/pbf -k move --show-traces

Every script under ``scenarios/`` and ``seed_examples/`` is written once against the seed's API
with ``pybullet_fleet`` imports, as a user's script would be. The incumbent runs it unchanged in
its venv; fleet_async runs it with the imports rewritten (``rewrite.map_imports``). Each run
prints a JSON trace (``parity_trace``); the harness diffs the two and prints, per script, the
differences, which seed module paths the script needed, which names fleet_async only has
privately, and whether the plain one-word rename would have imported at all. It also runs
each script on fleet_async with nothing but the rename (``pybullet_fleet`` -> ``fleet_async``,
``rewrite.plain_rename``) and reports whether that run completes with the same trace: the
promise made to a porting user.

Not part of CI: nothing under ``tests/`` imports this.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))

from parity_trace import MARKER  # noqa: E402  # the harness's own directory, added above
from rewrite import literal_import_check, map_imports, plain_rename  # noqa: E402
from tracediff import Difference, diff, show  # noqa: E402

SUITES = ("scenarios", "seed_examples")
NO_PLAIN_RENAME = "PARITY_NO_PLAIN_RENAME"
"""A script whose source holds this marker is not run with the plain rename (it inspects the
seed's ``pybullet_fleet.<module>`` paths itself, e.g. ``api_surface``)."""
SEED_NAME = "seed/000_3dffb1b59eacdbf9.txt"
# The seed (the API documentation) lives in the workspace's shared folder, beside the checkout.
SEED = next(
    (p / "shared" / SEED_NAME for p in REPO.parents if (p / "shared" / SEED_NAME).is_file()), None
)


@dataclass
class Run:
    """One script's result on one side."""

    trace: dict[str, Any] | None
    stderr_tail: str = ""
    returncode: int = 0


@dataclass
class Result:
    """One script on both sides, and what the import rewrite noticed."""

    name: str
    summary: str
    ours: Run
    incumbent: Run | None
    seed_modules: list[str] = field(default_factory=list)
    literal: list[str] = field(default_factory=list)
    differences: list[Difference] = field(default_factory=list)
    plain: Run | None = None
    plain_differences: list[Difference] = field(default_factory=list)

    @property
    def plain_ok(self) -> bool:
        """The script ran with the plain rename, as it did with the import mapping."""
        return (
            self.plain is not None
            and self.plain.trace is not None
            and self.plain.returncode == 0
            and not self.plain_differences
        )


def discover(suites: list[str], pattern: str | None) -> list[Path]:
    """The scripts to run, by suite then file name."""
    scripts = []
    for suite in suites:
        for path in sorted((HERE / suite).glob("*.py")):
            if path.name.startswith("_"):
                continue
            if pattern and pattern not in f"{suite}/{path.stem}":
                continue
            scripts.append(path)
    return scripts


def _env(pkg: str, extra_path: list[Path]) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONSTARTUP")}
    env["PYTHONPATH"] = os.pathsep.join(str(p) for p in [HERE, *extra_path])
    env["FLEET_PKG"] = pkg
    env["PARITY_DATA"] = str(HERE / "data")
    env["PYTHONHASHSEED"] = "0"
    if SEED is not None:
        env["PARITY_SEED"] = str(SEED)
    return env


def execute(python: str, script: Path, env: dict[str, str], timeout: float, cwd: Path) -> Run:
    """Run ``script`` and pick its trace out of stdout."""
    try:
        proc = subprocess.run(
            [python, str(script)],
            env=env,
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return Run(None, f"timed out after {timeout:g} s", -1)
    trace = None
    for line in proc.stdout.splitlines():
        if line.startswith(MARKER):
            trace = json.loads(line[len(MARKER) :])
    tail = "\n".join(proc.stderr.strip().splitlines()[-3:])
    return Run(trace, tail, proc.returncode)


def run_script(script: Path, incumbent_python: str | None, workdir: Path, timeout: float) -> Result:
    """Run one script on fleet_async (imports rewritten) and, if given, on the incumbent."""
    source = script.read_text()
    ported = map_imports(source)
    base = workdir / f"{script.parent.name}__{script.stem}"
    (base / "ours").mkdir(parents=True)
    (base / "incumbent").mkdir()
    local = base / script.name
    local.write_text(ported.source)
    ours = execute(sys.executable, local, _env("fleet_async", [REPO]), timeout, base / "ours")
    check = base / "literal_imports.py"
    check.write_text(literal_import_check(source))
    lit = subprocess.run(
        [sys.executable, str(check)],
        env=_env("fleet_async", [REPO]),
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )
    literal = [ln for ln in lit.stdout.splitlines() if ln.startswith("FAIL")]
    plain = None
    if NO_PLAIN_RENAME not in source:
        (base / "plain").mkdir()
        renamed = base / "plain" / script.name
        renamed.write_text(plain_rename(source))
        plain = execute(
            sys.executable, renamed, _env("fleet_async", [REPO]), timeout, base / "plain"
        )
    incumbent = None
    if incumbent_python:
        inc_env = _env("pybullet_fleet", [])
        incumbent = execute(incumbent_python, script, inc_env, timeout, base / "incumbent")
    summary = (source.split('"""')[1].strip().splitlines() or [""])[0] if '"""' in source else ""
    result = Result(
        f"{script.parent.name}/{script.stem}",
        summary,
        ours,
        incumbent,
        ported.seed_modules,
        literal,
        plain=plain,
    )
    if plain is not None:
        # The mapped script has one more line (the shim import): error texts quote line numbers.
        result.plain_differences = diff(
            _without_line_numbers(_comparable(ours)), _without_line_numbers(_comparable(plain))
        )
    if incumbent is not None:
        result.differences = diff(_comparable(incumbent), _comparable(ours))
    return result


def _without_line_numbers(value: Any) -> Any:
    """``value`` with the "(script line N)" of recorded errors taken out."""
    if isinstance(value, str):
        return re.sub(r" \(script line \d+\)", "", value)
    if isinstance(value, dict):
        return {k: _without_line_numbers(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_without_line_numbers(v) for v in value]
    return value


def _comparable(run: Run) -> dict[str, Any]:
    if run.trace is None:
        return {"_crash": run.stderr_tail or f"exit code {run.returncode}, no trace"}
    return {k: v for k, v in run.trace.items() if k != "_import_notes"}


def report(result: Result, show_traces: bool) -> None:
    """Print one script's result."""
    print(f"\n== {result.name}: {result.summary}")
    mods = ", ".join(f"pybullet_fleet.{m}" if m else "pybullet_fleet" for m in result.seed_modules)
    print(f"   seed imports: {mods or '-'}")
    for line in result.literal:
        print(f"   plain rename: {line}")
    plain = result.plain
    if plain is None:
        print("   plain rename: not applicable (the script reads the seed's module paths)")
    elif result.plain_ok:
        print("   plain rename: runs, same trace as with the import mapping")
    elif plain is not None and plain.trace is None:
        print(f"   plain rename: CRASHED: {plain.stderr_tail}")
    else:
        print(f"   plain rename: {len(result.plain_differences)} probes differ from the mapped run")
        for d in result.plain_differences:
            mapped, plain_value = show(d.incumbent, 50), show(d.ours)
            print(f"      {show(d.path, 40):40} mapped {mapped:50} plain {plain_value}")
    notes = (result.ours.trace or {}).get("_import_notes", [])
    for note in notes:
        print(
            f"   not public in fleet_async: {note['name']} (seed {note['seed_module']}), "
            f"found in {note['found_in']}"
        )
    if result.ours.trace is None:
        print(f"   fleet_async CRASHED: {result.ours.stderr_tail}")
    if result.incumbent is not None and result.incumbent.trace is None:
        print(f"   incumbent CRASHED: {result.incumbent.stderr_tail}")
    if result.incumbent is None:
        for key, value in sorted((result.ours.trace or {}).items()):
            if key != "_import_notes":
                print(f"   {key:34} {show(value, 100)}")
        return
    probes = len(set(_comparable(result.ours)) | set(_comparable(result.incumbent)))
    print(f"   {probes} probes, {len(result.differences)} differences")
    if result.differences:
        print(f"   {'where':40} {'incumbent (pybullet_fleet 0.8.0)':58}  fleet_async")
    for d in result.differences:
        print(f"   {show(d.path, 40):40} {show(d.incumbent):58}  {show(d.ours)}")
    if show_traces:
        print("   incumbent trace: " + json.dumps(result.incumbent.trace, sort_keys=True))
        print("   fleet_async trace: " + json.dumps(result.ours.trace, sort_keys=True))


def venv_python(venv: str) -> str:
    """The interpreter of a venv (or the path itself if it is an interpreter)."""
    path = Path(venv)
    for candidate in (path / "bin" / "python", path / "Scripts" / "python.exe", path):
        if candidate.is_file():
            return str(candidate)
    raise SystemExit(f"--incumbent: no Python interpreter found in {venv}")


def main(argv: list[str] | None = None) -> int:
    """Run the parity scripts and print the differences; exit 0 unless a script crashed on
    fleet_async or a seed example does not run with the plain rename."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--incumbent", help="venv (or python) with pybullet-fleet 0.8.0")
    parser.add_argument("-k", dest="pattern", help="only scripts whose suite/name contains this")
    parser.add_argument("--suite", choices=[*SUITES, "all"], default="all")
    parser.add_argument("--show-traces", action="store_true", help="print both full traces")
    parser.add_argument("--json", help="also write every trace and difference to this file")
    parser.add_argument("--jobs", type=int, default=min(4, os.cpu_count() or 1))
    parser.add_argument("--timeout", type=float, default=180.0, help="seconds per script")
    parser.add_argument("--seed", help="the seed text (default: shared/seed beside the checkout)")
    args = parser.parse_args(argv)
    if args.seed:
        global SEED  # one run, one seed; set before any script starts
        SEED = Path(args.seed)
    suites = list(SUITES) if args.suite == "all" else [args.suite]
    scripts = discover(suites, args.pattern)
    inc_python = venv_python(args.incumbent) if args.incumbent else None
    with (
        tempfile.TemporaryDirectory(prefix="parity-") as tmp,
        ThreadPoolExecutor(args.jobs) as pool,
    ):
        results = list(
            pool.map(lambda s: run_script(s, inc_python, Path(tmp), args.timeout), scripts)
        )
    for result in results:
        report(result, args.show_traces)
    crashed = [r.name for r in results if r.ours.trace is None]
    differing = [r.name for r in results if r.differences]
    print(
        f"\n{len(results)} scripts; {len(differing)} differ from the incumbent"
        + ("" if inc_python else " (incumbent not run)")
        + f"; {len(crashed)} crashed on fleet_async"
    )
    for suite in suites:
        mine = [r for r in results if r.name.startswith(suite + "/") and r.plain is not None]
        if mine:
            good = sum(r.plain_ok for r in mine)
            print(f"{suite}: {good}/{len(mine)} run on fleet_async with the plain rename")
    plain_failed = [
        r.name for r in results if r.name.startswith("seed_examples/") and not r.plain_ok
    ]
    if args.json:
        Path(args.json).write_text(
            json.dumps([_as_json(r) for r in results], indent=1, sort_keys=True)
        )
    return 1 if crashed or plain_failed else 0


def _as_json(result: Result) -> dict[str, Any]:
    return {
        "name": result.name,
        "seed_modules": result.seed_modules,
        "literal_rename": result.literal,
        "plain_rename_ok": result.plain_ok,
        "fleet_async": result.ours.trace,
        "incumbent": result.incumbent.trace if result.incumbent else None,
        "differences": [[d.path, d.incumbent, d.ours] for d in result.differences],
    }


if __name__ == "__main__":
    sys.exit(main())
