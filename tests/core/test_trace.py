"""Traces: what sim.start_trace records, read back with TraceReader; format errors."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MoveAction,
    MultiRobotSimulationCore,
    Path,
    PickAction,
    Pose,
    ShapeParams,
    SimObject,
)
from fleet_async.core.view.trace import TraceWriter
from fleet_async.core.view.trace.format import FORMAT_VERSION, HEADER, MAGIC, YAW_SCALE
from fleet_async.core.view.trace.frames import HeadingTracker
from fleet_async.viewer import TraceCutWarning, TraceFormatError, TraceReader
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.1], rgba_color=[0.2, 0.4, 0.9, 1.0])
TOTE = ShapeParams("box", half_extents=[0.15, 0.15, 0.08], rgba_color=[0.9, 0.5, 0.1, 1.0])


def robot(sim, x=0.0, y=0.0, name="r"):
    return Agent.from_params(
        AgentSpawnParams(
            visual_shape=BOX,
            collision_shape=BOX,
            initial_pose=Pose.from_xyz(x, y, 0.1),
            name=name,
            controller={"type": "omni", "max_linear_vel": 1.0},
        ),
        sim,
    )


def tote(sim, x, y, name="tote"):
    return SimObject.from_mesh(
        visual_shape=TOTE,
        collision_shape=TOTE,
        pose=Pose.from_xyz(x, y, 0.08),
        sim_core=sim,
        name=name,
    )


def test_frames_hold_every_body_pose_per_step(sim, tmp_path):
    a, b = robot(sim, 0, 0, "a"), robot(sim, 5, 0, "b")
    b.set_pose(Pose.from_euler(5.0, 0.0, 0.1, yaw=math.pi / 2))
    a.add_action(MoveAction(path=Path([Pose.from_xyz(2, 0, 0.1)])))
    path = tmp_path / "run.fatrace"
    writer = sim.start_trace(path)
    expected = []
    for _ in range(5):
        sim.step_once()
        expected.append(sim.get_poses([a.object_id, b.object_id])[0].astype(np.float32))
    assert sim.stop_trace() == str(path)
    assert not writer.is_tracing
    reader = TraceReader(path)
    frames = list(reader.frames())
    assert [f.step for f in frames] == [0, 1, 2, 3, 4, 5]
    assert reader.frame_count == 6 and reader.end["last_step"] == 5
    for frame, want in zip(frames[1:], expected, strict=True):
        assert frame.ids.tolist() == [a.object_id, b.object_id]
        np.testing.assert_array_equal(frame.position, want)
    assert frames[-1].yaw[1] == pytest.approx(math.pi / 2, abs=1e-4)
    assert frames[-1].flags[0] & 1 and not frames[-1].flags[1] & 1  # a moves, b stands
    assert reader.meta["timestep"] == 0.1 and reader.version == FORMAT_VERSION


@pytest.mark.parametrize("turned", [0, 3, 40])
def test_headings_recomputed_only_where_they_changed_match_a_full_computation(turned):
    rng = np.random.default_rng(turned)

    def random_quats(n):
        q = rng.normal(size=(n, 4))
        return q / np.linalg.norm(q, axis=1, keepdims=True)

    def full(q):
        x, y, z, w = q.T
        yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        return np.rint(yaw / YAW_SCALE)

    quats = random_quats(100)
    tracker, out = HeadingTracker(100), np.empty(100, dtype=np.int16)
    for _ in range(3):
        tracker.update(quats, out)
        gap = np.abs(out - full(quats))
        assert np.minimum(gap, 65534 - gap).max() <= 1  # float32 rounding; +-pi wrap
        quats[:turned] = random_quats(turned)


def test_bodies_carry_kind_shape_colour_and_static_pose(sim, tmp_path):
    robot(sim, name="bot")
    tote(sim, 1, 1)
    shelf = SimObject.from_mesh(
        visual_shape=BOX,
        collision_shape=BOX,
        pose=Pose.from_xyz(3, 4, 0.1),
        sim_core=sim,
        collision_mode="static",
        name="shelf",
    )
    sim.start_trace(tmp_path / "t.fatrace")
    sim.step_once()
    sim.stop_trace()
    reader = TraceReader(tmp_path / "t.fatrace")
    kinds = {b["name"]: b["kind"] for b in reader.bodies.values()}
    assert kinds == {"bot": "agent", "tote": "object", "shelf": "static"}
    bot = next(b for b in reader.bodies.values() if b["name"] == "bot")
    shape = reader.shapes[bot["shape"]]
    assert shape["type"] == "box" and shape["half"] == [0.3, 0.2]
    assert shape["rgba"] == [0.2, 0.4, 0.9, 1.0] and shape["z"] == [-0.1, 0.1]
    static = reader.bodies[shelf.object_id]
    assert static["pose"] == pytest.approx([3, 4, 0.1, 0.0])
    # Static bodies are described once, not repeated in every frame.
    assert shelf.object_id not in next(reader.frames()).ids.tolist()


def test_every_n_steps_and_fps(sim, tmp_path):
    robot(sim)
    sim.start_trace(tmp_path / "a.fatrace", every_n_steps=3)
    for _ in range(7):
        sim.step_once()
    sim.stop_trace()
    assert [f.step for f in TraceReader(tmp_path / "a.fatrace").frames()] == [0, 3, 6, 7]
    writer = sim.start_trace(tmp_path / "b.fatrace", fps=5)  # dt 0.1 s: every 2 steps
    assert writer.every_n_steps == 2
    sim.stop_trace()
    with pytest.raises(ValueError, match="every_n_steps or fps"):
        sim.start_trace(tmp_path / "c.fatrace", every_n_steps=2, fps=5)
    with pytest.raises(ValueError, match="every_n_steps"):
        TraceWriter(sim, tmp_path / "d.fatrace", every_n_steps=0)


def test_action_events_and_carrying_flag(sim, tmp_path):
    bot = robot(sim, 0, 0)
    box = tote(sim, 2, 0)
    bot.add_action(PickAction(target_object_id=box, approach_offset=0.5))
    bot.add_action(MoveAction(path=Path([Pose.from_xyz(0, 3, 0.1)])))
    sim.start_trace(tmp_path / "p.fatrace")
    for _ in range(200):
        sim.step_once()
    sim.stop_trace()
    reader = TraceReader(tmp_path / "p.fatrace")
    mine = [
        (e["kind"], e["data"]["action"]) for e in reader.events if e["object_id"] == bot.object_id
    ]
    assert mine[:2] == [("action_started", "PickAction"), ("action_ended", "PickAction")]
    ended = [e for e in reader.events if e["kind"] == "action_ended"]
    assert ended[0]["data"]["status"] == "completed"
    assert (ended[0]["t"], ended[0]["step"]) == (pytest.approx(3.1), 31)
    last = list(reader.frames())[-1]
    index = last.ids.tolist().index(bot.object_id)
    assert last.flags[index] & 2  # carrying the tote


def test_failed_action_sets_the_failed_flag(sim, tmp_path):
    bot = robot(sim)
    bot.add_action(PickAction(target_object_id=12345))  # no such object: the pick fails
    sim.start_trace(tmp_path / "f.fatrace")
    for _ in range(3):
        sim.step_once()
    sim.stop_trace()
    reader = TraceReader(tmp_path / "f.fatrace")
    ended = [e for e in reader.events if e["kind"] == "action_ended"]
    assert ended and ended[0]["data"]["status"] == "failed" and ended[0]["data"]["reason"]
    assert list(reader.frames())[-1].flags[0] & 4


def test_collisions_start_and_end(sim, tmp_path):
    a, b = robot(sim, 0, 0, "a"), robot(sim, 3, 0, "b")
    a.add_action(MoveAction(path=Path([Pose.from_xyz(3, 0, 0.1), Pose.from_xyz(3, 4, 0.1)])))
    sim.start_trace(tmp_path / "c.fatrace")
    for _ in range(150):
        sim.step_once()
    sim.stop_trace()
    hits = TraceReader(tmp_path / "c.fatrace").collisions()
    assert hits["started"].tolist()[:2] == [1, 0]
    assert sorted([hits["a"][0], hits["b"][0]]) == [a.object_id, b.object_id]
    assert hits["step"][0] < hits["step"][1]


def test_a_collision_with_a_removed_body_ends_under_its_id(sim, tmp_path):
    a, b = robot(sim, 0, 0, "a"), robot(sim, 0.5, 0, "b")
    sim.step_once()
    assert sim.get_active_collision_pairs() == [(a.object_id, b.object_id)]
    sim.start_trace(tmp_path / "r.fatrace")  # the pair already touching starts in frame 0
    sim.step_once()
    b_id = b.object_id
    sim.remove_object(b)
    sim.step_once()
    sim.stop_trace()
    hits = TraceReader(tmp_path / "r.fatrace").collisions()
    assert hits["step"].tolist() == [1, 3]
    assert hits["started"].tolist() == [1, 0]
    assert hits["a"].tolist() == [a.object_id] * 2 and hits["b"].tolist() == [b_id] * 2


def test_trace_event_hook_and_spawns_mid_run(sim, tmp_path):
    robot(sim)
    sim.trace_event("ignored")  # no trace running: a no-op
    sim.start_trace(tmp_path / "e.fatrace")
    sim.step_once()
    late = robot(sim, 4, 4, "late")
    late_id = late.object_id
    sim.trace_event("mission_error", object_id=late_id, message="boom", when=object())
    sim.step_once()
    sim.remove_object(late)
    sim.step_once()
    sim.stop_trace()
    reader = TraceReader(tmp_path / "e.fatrace")
    kinds = [(e["kind"], e["object_id"]) for e in reader.events]
    assert ("mission_error", late_id) in kinds and ("removed", late_id) in kinds
    error = next(e for e in reader.events if e["kind"] == "mission_error")
    assert error["data"]["message"] == "boom" and isinstance(error["data"]["when"], str)
    counts = [len(f.ids) for f in reader.frames()]
    assert counts == [1, 1, 2, 1]
    assert reader.bodies[late_id]["name"] == "late"


def test_close_and_reset_finish_the_trace(tmp_path):
    sim = MultiRobotSimulationCore(headless_params())
    robot(sim)
    sim.start_trace(tmp_path / "x.fatrace")
    with pytest.raises(RuntimeError, match="already running"):
        sim.start_trace(tmp_path / "y.fatrace")
    sim.step_once()
    sim.reset()
    assert sim.tracer is None
    assert TraceReader(tmp_path / "x.fatrace").end is not None
    sim.start_trace(tmp_path / "z.fatrace")
    sim.close()
    assert TraceReader(tmp_path / "z.fatrace").end is not None


def test_same_seed_same_trace(tmp_path):
    def run(name):
        with MultiRobotSimulationCore(headless_params()) as sim:
            bots = [robot(sim, i, 0, f"r{i}") for i in range(4)]
            for i, bot in enumerate(bots):
                bot.add_action(MoveAction(path=Path([Pose.from_xyz(i, 3 + i, 0.1)])))
            sim.start_trace(tmp_path / name)
            for _ in range(40):
                sim.step_once()
        reader = TraceReader(tmp_path / name)
        return reader, [
            (f.step, f.position.tobytes(), f.yaw.tobytes(), f.flags.tobytes())
            for f in reader.frames()
        ]

    (r1, f1), (r2, f2) = run("1.fatrace"), run("2.fatrace")
    assert f1 == f2 and r1.events == r2.events and r1.bodies == r2.bodies


# ----- errors a reader reports -----------------------------------------------------------------


@pytest.fixture
def small_trace(sim, tmp_path):
    robot(sim)
    sim.start_trace(tmp_path / "ok.fatrace")
    for _ in range(3):
        sim.step_once()
    sim.stop_trace()
    return tmp_path / "ok.fatrace"


def test_truncated_file_names_file_problem_and_version(small_trace, tmp_path):
    data = small_trace.read_bytes()
    cut = tmp_path / "cut.fatrace"
    cut.write_bytes(data[: len(data) - 30])
    with pytest.raises(TraceFormatError) as err:
        TraceReader(cut, strict=True)
    message = str(err.value)
    assert str(cut) in message and "truncated" in message and "versions 1 and 2" in message
    # By default the readable prefix loads, with a warning (a killed run's trace).
    with pytest.warns(TraceCutWarning, match=r"cut\.fatrace: truncated: record 4 \(END\)"):
        prefix = TraceReader(cut)
    assert prefix.frame_count == TraceReader(small_trace).frame_count and prefix.end is None
    assert prefix.cut.startswith("truncated: record 4 (END) at byte")
    cut.write_bytes(data[:10])
    with pytest.raises(TraceFormatError, match="shorter than the 16-byte header"):
        TraceReader(cut)


def test_missing_end_record_is_unfinished(sim, tmp_path):
    robot(sim)
    writer = sim.start_trace(tmp_path / "live.fatrace")
    for _ in range(3):
        sim.step_once()
    writer.flush()  # what the periodic flush of a long run leaves on disk
    with pytest.raises(TraceFormatError, match="no end record"):
        TraceReader(tmp_path / "live.fatrace", strict=True)
    with pytest.warns(TraceCutWarning, match="no end record"):
        assert TraceReader(tmp_path / "live.fatrace").frame_count >= 1
    assert TraceReader(tmp_path / "live.fatrace", allow_unfinished=True).frame_count >= 1
    sim.stop_trace()


def test_other_version_and_not_a_trace(small_trace, tmp_path):
    data = bytearray(small_trace.read_bytes())
    struct.pack_into("<H", data, 8, 99)
    other = tmp_path / "v99.fatrace"
    other.write_bytes(bytes(data))
    with pytest.raises(TraceFormatError) as err:
        TraceReader(other)
    assert "format version is 99" in str(
        err.value
    ) and "reads trace format versions 1 and 2" in str(err.value)
    junk = tmp_path / "junk.fatrace"
    junk.write_bytes(b"hello world, this is not a trace at all")
    with pytest.raises(TraceFormatError, match="not a fleet_async trace"):
        TraceReader(junk)
    assert HEADER.unpack_from(small_trace.read_bytes())[0] == MAGIC


def test_scenario_trace_section(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    config = {
        "simulation": {"gui": False, "monitor": False, "timestep": 0.1},
        "entities": [{"name": "r", "visual_shape": {"shape_type": "box"}}],
        "trace": {"path": "scn.fatrace", "every_n_steps": 2},
    }
    with MultiRobotSimulationCore.from_dict(config) as sim:
        for _ in range(4):
            sim.step_once()
    assert [f.step for f in TraceReader(tmp_path / "scn.fatrace").frames()] == [0, 2, 4]
    config["trace"] = {"file": "x.fatrace"}
    with pytest.raises(ValueError, match=r"trace: unknown key 'file'"):
        MultiRobotSimulationCore.from_dict(config)


# ----- the trace beside skipped steps, lazily created bodies and missions ---------------------


def test_a_trace_leaves_empty_steps_skippable_and_holds_the_pose_over_a_span(sim, tmp_path):
    bot = robot(sim, 0, 0, "bot")
    bot.add_action(MoveAction(path=Path([Pose.from_xyz(1, 0, 0.1)])))
    sim.step_once()
    sim.start_trace(tmp_path / "s.fatrace", every_n_steps=4)
    while sim.idle_steps(1) == 0:  # the move runs step by step
        sim.step_once()
    moved_until = sim.step_count  # bot stands from here on
    assert sim.idle_steps(50) == 50  # the trace does not keep the drivers from skipping
    assert sim.skip_idle_steps(50) == 50
    bot.add_action(MoveAction(path=Path([Pose.from_xyz(1, 1, 0.1)])))
    for _ in range(3):
        sim.step_once()
    sim.stop_trace()
    reader = TraceReader(tmp_path / "s.fatrace")
    frames = list(reader.frames())
    span_first = -(-(moved_until + 1) // 4) * 4  # the span's first and last frame slots
    span_last = (moved_until + 50) // 4 * 4
    run = list(range(4, moved_until + 1, 4))
    after = [s for s in range(moved_until + 51, moved_until + 54) if s % 4 == 0]
    assert [f.step for f in frames] == [1, *run, span_first, span_last, *after, moved_until + 53]
    held = [f for f in frames if moved_until <= f.step <= moved_until + 50]
    np.testing.assert_array_equal(held[0].position, held[-1].position)
    assert held[-1].position[0].tolist() == pytest.approx([1.0, 0.0, 0.1])
    assert not held[-1].flags[0] & 1  # not moving over the span


def test_pending_bodies_are_described_without_creating_them_all(tmp_path):
    with MultiRobotSimulationCore(headless_params()) as sim:
        bots = [robot(sim, i, 0, f"r{i}") for i in range(20)]
        assert sim.world.has_pending_bodies
        sim.start_trace(tmp_path / "p.fatrace")
        for _ in range(3):
            sim.step_once()
        sim.stop_trace()
        created = [b for b in bots if b.raw_body_id >= 0]
        assert len(created) == 1  # measured once, for the fleet's one shape
        reader = TraceReader(tmp_path / "p.fatrace")
        shapes = {reader.bodies[b.object_id]["shape"] for b in bots}
        assert len(shapes) == 1
        shape = reader.shapes[shapes.pop()]
        assert shape["half"] == [0.3, 0.2] and shape["rgba"] == [0.2, 0.4, 0.9, 1.0]


@pytest.mark.parametrize("backend", ["asyncio", "trio"])
def test_mission_errors_are_logged_once_each(sim, tmp_path, backend):
    import fleet_async as fa

    robot(sim)
    sim.start_trace(tmp_path / "m.fatrace")

    async def child():
        await sim.sleep(1.0)
        raise ValueError("boom")

    async def main():
        async with sim.task_group() as tg:  # the error reaches main again, in a group
            tg.start_soon(child)

    with pytest.raises(ValueError, match="boom"):
        fa.run(sim, main, backend=backend)
    sim.stop_trace()
    errors = [e for e in TraceReader(tmp_path / "m.fatrace").events if e["kind"] == "mission_error"]
    assert len(errors) == 1
    assert errors[0]["data"]["error"] == "ValueError" and errors[0]["data"]["message"] == "boom"
    assert errors[0]["t"] == pytest.approx(1.0)
