"""Every example runs headless, to completion, within a step limit."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("*.py"))


def test_there_are_examples():
    assert EXAMPLES


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_example_runs_headless(example):
    result = subprocess.run(
        [sys.executable, str(example), "--max-steps", "2000"],
        capture_output=True,
        text=True,
        timeout=300,
        env={k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")},
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.strip(), "an example must print what the fleet did"
