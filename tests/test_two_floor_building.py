"""The two-floor building example tells the same story on both backends (deterministic)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "two_floor_building.py"


def run_example(backend: str, capsys, *extra: str) -> str:
    spec = importlib.util.spec_from_file_location("two_floor_building", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.main(["--backend", backend, "--max-steps", "2000", *extra]) == 0
    return capsys.readouterr().out


def test_the_example_is_the_same_on_asyncio_and_trio(capsys):
    on_asyncio = run_example("asyncio", capsys)
    assert "4/4 items delivered" in on_asyncio
    assert "lift: L1 -> L2 (tree0)" in on_asyncio and "lift: L1 -> L2 (mission0)" in on_asyncio
    assert run_example("trio", capsys) == on_asyncio


def test_the_example_traces_for_the_viewer(capsys, tmp_path):
    from fleet_async.viewer import TraceReader

    path = tmp_path / "building.fatrace"
    out = run_example("asyncio", capsys, "--trace", str(path))
    assert f"fleet-async view {path}" in out
    reader = TraceReader(path)
    agents = [b for b in reader.bodies.values() if b["kind"] == "agent"]
    devices = sorted(b["class"] for b in agents if b.get("device"))
    assert len(agents) - len(devices) == 4  # the couriers
    assert devices == ["Door", "Elevator", "Workcell", "Workcell"]  # dispenser and ingestor
    top = max(float(f.position[:, 2].max()) for f in reader.frames())
    assert top > 3.0  # the couriers reach the upper floor
