"""The trace reader trusts nothing in a file: only its own error, with the record and byte;
a trace that ends early (a killed run) shows its readable prefix, with a warning."""

from __future__ import annotations

import os
import signal
import struct
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from fleet_async import Agent, AgentSpawnParams, Pose, ShapeParams
from fleet_async.core.view.trace.format import HEADER, RECORD, RecordKind
from fleet_async.viewer import TraceCutWarning, TraceFormatError, TraceReader

CUBE = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


@pytest.fixture
def trace(sim, tmp_path) -> Path:
    for i in range(3):
        Agent.from_params(
            AgentSpawnParams(
                visual_shape=CUBE,
                collision_shape=CUBE,
                initial_pose=Pose.from_xyz(0.15 * i, 0, 0.1),
                controller="omni",
            ),
            sim,
        ).set_goal_pose(Pose.from_xyz(2.0, 1.0, 0.1))
    sim.start_trace(tmp_path / "ok.fatrace", every_n_steps=1)
    sim.trace_event("note", text="hello")
    for _ in range(8):
        sim.step_once()
    sim.stop_trace()
    return tmp_path / "ok.fatrace"


def _records(data: bytes) -> list[tuple[int, int, bytes]]:
    """(offset, kind, payload) of every record."""
    out, offset = [], HEADER.size
    while offset < len(data):
        kind, length = RECORD.unpack_from(data, offset)
        out.append((offset, kind, data[offset + 8 : offset + 8 + length]))
        offset += 8 + length + (-length % 4)
    return out


def _with_payload(data: bytes, kind: int, payload: bytes) -> bytes:
    """The trace with the first record of ``kind`` holding ``payload`` instead."""
    out = bytearray(data[: HEADER.size])
    done = False
    for _, k, old in _records(data):
        body = payload if (k == kind and not done) else old
        done = done or k == kind
        out += RECORD.pack(k, len(body)) + body + bytes(-len(body) % 4)
    return bytes(out)


BAD_JSON = [
    b"\xff\xfe not utf-8",
    b"{not json",
    b"[" * 100_000 + b"]" * 100_000,  # deep enough for RecursionError
    b"[]",
    b'"a string"',
]


@pytest.mark.parametrize(
    "kind", [RecordKind.META, RecordKind.BODIES, RecordKind.EVENTS, RecordKind.END]
)
@pytest.mark.parametrize("payload", BAD_JSON, ids=["utf8", "json", "deep", "list", "str"])
def test_bad_json_payloads_raise_the_format_error_with_record_and_byte(
    trace, tmp_path, kind, payload
):
    bad = tmp_path / "bad.fatrace"
    data = trace.read_bytes()
    bad.write_bytes(_with_payload(data, kind, payload))
    offset = next(o for o, k, _ in _records(data) if k == kind)
    with pytest.raises(TraceFormatError, match=rf"\({kind.name}\) at byte {offset}: "):
        TraceReader(bad)


SHAPED = {
    RecordKind.META: [b'{"timestep": "fast"}', b'{"timestep": -1}', b"{}"],
    RecordKind.BODIES: [
        b'{"shapes": [], "bodies": {}}',
        b'{"shapes": [], "bodies": [{"id": "x"}]}',
    ],
    RecordKind.EVENTS: [b'{"events": [[1, 2]]}', b'{"events": 5}'],
    RecordKind.LAYOUT: [struct.pack("<I", 1 << 30), b"\x01"],
    RecordKind.FRAMES: [struct.pack("<II", 1 << 20, 3), struct.pack("<II", 2, 1 << 20), b""],
    RecordKind.COLLISIONS: [struct.pack("<I", 1 << 28)],
}


@pytest.mark.parametrize(("kind", "payload"), [(k, p) for k, ps in SHAPED.items() for p in ps])
def test_payloads_of_the_wrong_shape_raise_the_format_error(trace, tmp_path, kind, payload):
    data = trace.read_bytes()
    if kind not in {k for _, k, _ in _records(data)}:
        pytest.skip(f"no {kind.name} record in this trace")
    bad = tmp_path / "bad.fatrace"
    bad.write_bytes(_with_payload(data, kind, payload))
    with pytest.raises(TraceFormatError, match=rf"record \d+ \({kind.name}\) at byte \d+: "):
        TraceReader(bad)


def test_random_corruption_raises_nothing_but_the_format_error(trace, tmp_path):
    data = trace.read_bytes()
    rng = np.random.default_rng(26)
    bad = tmp_path / "bad.fatrace"
    outcomes = {"read": 0, "refused": 0}
    for _ in range(300):
        corrupted = bytearray(data)
        for at in rng.integers(0, len(data), size=int(rng.integers(1, 4))):
            corrupted[int(at)] = int(rng.integers(0, 256))
        cut = int(rng.integers(len(data) // 2, len(data) + 1))
        bad.write_bytes(bytes(corrupted[:cut]))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", TraceCutWarning)
            try:
                reader = TraceReader(bad)
                list(reader.frames())
                reader.collisions()
                outcomes["read"] += 1
            except TraceFormatError:
                outcomes["refused"] += 1
    assert outcomes["read"] and outcomes["refused"]  # both kinds of file were tried


_WRITER = """
import sys, time
from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimulationParams
box = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])
sim = MultiRobotSimulationCore(SimulationParams(gui=False, target_rtf=0.0, timestep=0.1))
robot = Agent.from_mesh(box, box, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")
robot.set_goal_pose(Pose.from_xyz(50, 0, 0.1))
sim.start_trace(sys.argv[1], flush_seconds=1e-9)
while True:
    sim.step_once()
    time.sleep(0.001)
"""


def test_the_trace_of_a_killed_run_loads_its_prefix_with_a_warning(tmp_path):
    path = tmp_path / "killed.fatrace"
    writer = subprocess.Popen([sys.executable, "-c", _WRITER, str(path)], env=dict(os.environ))
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if path.exists() and path.stat().st_size > 4000:
                break
            time.sleep(0.05)
        else:
            pytest.fail("the writer wrote nothing")
    finally:
        writer.send_signal(signal.SIGKILL)
        writer.wait()
    with pytest.warns(TraceCutWarning, match=r"killed\.fatrace: truncated: .*readable prefix"):
        reader = TraceReader(path)
    assert reader.end is None and reader.cut is not None and reader.frame_count >= 1
    steps = [f.step for f in reader.frames()]
    assert steps == sorted(steps)
    with pytest.raises(TraceFormatError, match="truncated"):
        TraceReader(path, strict=True)


def test_nothing_before_the_meta_record_is_an_error(trace, tmp_path):
    data = trace.read_bytes()
    first = _records(data)[0]
    cut = tmp_path / "cut.fatrace"
    cut.write_bytes(data[: first[0] + 8 + 3])
    with pytest.raises(TraceFormatError, match="nothing to show before it"):
        TraceReader(cut)
