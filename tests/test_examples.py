"""Every example runs headless, to completion, within a step limit."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("*.py"))
# Examples whose defaults are big (a thousand robots) run small here, to keep the suite fast.
SMALL = {"mapf_warehouse.py": ["--robots", "40", "--duration", "30"]}


def test_there_are_examples():
    assert EXAMPLES


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_example_runs_headless(example):
    result = subprocess.run(
        [sys.executable, str(example), "--max-steps", "2000", *SMALL.get(example.name, [])],
        capture_output=True,
        text=True,
        timeout=300,
        env={k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")},
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.strip(), "an example must print what the fleet did"
    # A shipped example teaches by example: it must not trip the library's warnings, which
    # go to stderr (PyBullet's build banner is the only line expected there).
    noise = [
        line
        for line in result.stderr.splitlines()
        if line.strip() and not line.startswith("pybullet build time")
    ]
    assert not noise, f"{example.name} warned:\n" + "\n".join(noise)


def test_example_names_are_unique_and_descriptions_whole():
    from fleet_async.cli.examples import list_examples

    examples = list_examples(EXAMPLES[0].parent)
    names = [example.name for example in examples]
    assert len(names) == len(set(names)), names
    for example in examples:
        # A whole sentence (or question), not a first line cut mid-sentence.
        assert example.description.endswith((".", "?")), (example.name, example.description)
