"""The documentation site: every code example runs, and the scenario reference is complete.

Every fenced ``python`` block of ``docs/*.md`` and ``README.md`` runs here, headless, each in a
fresh interpreter (a working directory where ``examples/`` is the repository's), as SimPy runs
its documentation's examples. A block that defines ``test_...`` functions runs under pytest
(with the ``fleet_sim`` fixture of ``fleet_async.testing``). A block preceded by
``<!-- no-run -->`` is only shown; keep those few (installs, fragments).
"""

from __future__ import annotations

import ast
import dataclasses
import os
import subprocess
import sys
from pathlib import Path

import pytest
from docs_blocks import Block, fenced_blocks

REPO = Path(__file__).resolve().parent.parent
DOCS = REPO / "docs"
PAGES = [REPO / "README.md", *sorted(DOCS.glob("*.md"))]
PYTHON_BLOCKS = [
    block for page in PAGES for block in fenced_blocks(page) if block.language == "python"
]

sys.path.insert(0, str(DOCS / "hooks"))
import scenario_reference  # noqa: E402  # the generator lives with the docs, not the package


def headless_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO), env.get("PYTHONPATH", "")]))
    return env


def defines_tests(code: str) -> bool:
    tree = ast.parse(code)
    return any(
        isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name.startswith("test_")
        for node in tree.body
    )


def run_block(block: Block, workdir: Path) -> subprocess.CompletedProcess[str]:
    """Run one block as a user would paste it: a script, or a pytest file."""
    (workdir / "examples").symlink_to(REPO / "examples")
    if defines_tests(block.code):
        path = workdir / "test_from_docs.py"
        path.write_text(block.code)
        argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(path)]
    else:
        path = workdir / "example_from_docs.py"
        path.write_text(block.code)
        argv = [sys.executable, str(path)]
    return subprocess.run(
        argv, cwd=workdir, env=headless_env(), capture_output=True, text=True, timeout=300
    )


def test_the_docs_have_python_examples():
    assert len([b for b in PYTHON_BLOCKS if b.runs]) >= 5


@pytest.mark.parametrize("block", [b for b in PYTHON_BLOCKS if b.runs], ids=lambda b: b.id)
def test_every_python_example_runs(block, tmp_path):
    result = run_block(block, tmp_path)
    assert result.returncode == 0, (
        f"{block.id} failed:\n{block.code}\n--- stdout\n{result.stdout}\n--- stderr\n"
        f"{result.stderr}"
    )


def test_skipped_python_examples_are_few():
    skipped = [b.id for b in PYTHON_BLOCKS if not b.runs]
    assert len(skipped) <= 3, f"too many <!-- no-run --> python blocks: {skipped}"


def test_every_python_example_parses():
    for block in PYTHON_BLOCKS:
        try:
            ast.parse(block.code)
        except SyntaxError as exc:
            pytest.fail(f"{block.id}: {exc}")


YAML_BLOCKS = [
    block
    for page in PAGES
    for block in fenced_blocks(page)
    if block.language in ("yaml", "yml") and block.runs
]


@pytest.mark.parametrize("block", YAML_BLOCKS, ids=lambda b: b.id)
def test_every_yaml_scenario_example_loads(block):
    """A YAML block is a scenario whose paths are relative to examples/scenarios/."""
    import yaml

    from fleet_async import MultiRobotSimulationCore

    config = yaml.safe_load(block.code)
    config.setdefault("simulation", {}).update(gui=False, target_rtf=0)
    sim = MultiRobotSimulationCore.from_dict(
        config, source=block.id, base_dir=REPO / "examples" / "scenarios"
    )
    sim.close()


# ----- the scenario reference -------------------------------------------------------------------


def test_the_scenarios_page_carries_the_generated_reference():
    assert scenario_reference.MARKER in (DOCS / "scenarios.md").read_text()


def test_every_key_of_the_reference_has_a_description():
    missing = [
        f"{heading}: {key.name}"
        for heading, _, keys in scenario_reference.sections()
        for key in keys
        if not key.text.strip()
    ]
    assert missing == []


def test_the_reference_covers_every_section_field_action_and_plugin():
    from fleet_async.core.agents.agent_plugins import AGENT_PLUGIN_REGISTRY
    from fleet_async.core.base.params import SimulationParams
    from fleet_async.core.scenario import build, entities, missions, world_config

    parts = {heading: {k.name for k in keys} for heading, _, keys in scenario_reference.sections()}
    assert parts["Top level"] == set(build.SCENARIO_SECTIONS)
    assert parts["simulation"] == {f.name for f in dataclasses.fields(SimulationParams)}
    assert parts["world"] == {*world_config.SOURCE_KEYS, *world_config.OPTION_KEYS}
    assert parts["plugins"] == set(build.PLUGIN_KEYS)
    assert parts["missions"] == set(missions.MISSION_KEYS)
    assert parts["trace"] == set(build.TRACE_KEYS)
    assert set(entities.SCENARIO_ENTITY_KEYS) <= parts["entities"]
    for name in entities.ACTION_TYPES:
        assert f"actions (type: {name})" in parts
    for name in AGENT_PLUGIN_REGISTRY:
        assert f"plugins of an agent (type: {name})" in parts
    for kind in build.MANAGER_TYPES:
        assert f"managers (type: {kind})" in parts


def test_the_hand_written_key_texts_match_the_loader():
    from fleet_async.core.scenario import build, missions, world_config

    ref = scenario_reference
    assert set(ref.SECTION_TEXT) == set(build.SCENARIO_SECTIONS)
    assert set(ref.WORLD_TEXT) == {*world_config.SOURCE_KEYS, *world_config.OPTION_KEYS}
    assert set(ref.PLUGIN_TEXT) == set(build.PLUGIN_KEYS)
    assert set(ref.MISSION_TEXT) == set(missions.MISSION_KEYS)
    assert set(ref.TRACE_TEXT) == set(build.TRACE_KEYS)


def test_docstring_sections_are_read_with_shared_and_continued_entries():
    class Example:
        """Example.

        Args:
            first: One line.
            second / third: Shared text
                that goes on.
        """

    assert scenario_reference.docstring_entries(Example) == {
        "first": "One line.",
        "second": "Shared text that goes on.",
        "third": "Shared text that goes on.",
    }
