"""Checkpoints hold plain data: reading one runs no code, and a refusal changes nothing."""

from __future__ import annotations

import io
import json
import os
import pickle
from pathlib import Path

import numpy as np
import pytest

from fleet_async import (
    Agent,
    AgentPlugin,
    CheckpointError,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimulationParams,
)
from fleet_async.core.checkpoint.saving import collect
from tests.core.checkpoint_scene import build, digest, trace

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


class _Payload:
    """What an attacker plants: unpickling it writes a marker file."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple[object, tuple[str]]:
        return (eval, (f"open({str(self.marker)!r}, 'w').write('pwned')",))


@pytest.fixture
def warm(tmp_path: Path) -> tuple[Path, MultiRobotSimulationCore]:
    sim = build()
    for _ in range(40):
        sim.step_once()
    path = tmp_path / "warm.ckpt"
    sim.save_state(path)
    yield path, sim
    sim.close()


def _poses(sim: MultiRobotSimulationCore) -> np.ndarray:
    position, orientation = sim.get_poses([o.object_id for o in sim.sim_objects])
    return np.concatenate([position, orientation], axis=1)


def test_a_planted_pickle_runs_nothing_and_names_the_file(tmp_path):
    marker = tmp_path / "marker"
    planted = tmp_path / "gift.ckpt"
    planted.write_bytes(pickle.dumps(_Payload(marker)))
    sim = build()
    with (
        sim,
        pytest.raises(CheckpointError, match=r"gift\.ckpt is a format-1 checkpoint, a pickle"),
    ):
        sim.restore_state(planted)
    assert not marker.exists()
    # Behind the explicit flag the pickle is read (and so its code runs): that is what
    # unsafe means, and why it is not the default.
    sim = build()
    with sim, pytest.raises(CheckpointError):
        sim.restore_state(planted, unsafe=True)
    assert marker.read_text() == "pwned"


def test_a_checkpoint_is_a_zip_of_json_and_arrays_without_pickles(warm):
    path, _ = warm
    with np.load(path, allow_pickle=False) as archive:
        header = json.loads(archive["header"].tobytes())
        assert header["version"] == 2 and header["format"] == "fleet_async checkpoint"
        assert all(archive[name].dtype != object for name in archive.files)


def test_a_crafted_state_cannot_name_foreign_classes(warm, tmp_path):
    path, _ = warm
    with np.load(path, allow_pickle=False) as archive:
        members = {name: archive[name] for name in archive.files}
    evil = {"obj_of": [0, "os:system", {}]}
    members["state"] = np.frombuffer(json.dumps(evil).encode(), dtype=np.uint8)
    crafted = tmp_path / "crafted.ckpt"
    buffer = io.BytesIO()
    np.savez(buffer, **members)
    crafted.write_bytes(buffer.getvalue())
    sim = build()
    with (
        sim,
        pytest.raises(CheckpointError, match=r"crafted\.ckpt is damaged .*not one of fleet_async"),
    ):
        sim.restore_state(crafted)
    for junk in (b"PK\x03\x04 cut", b"", json.dumps({"a": 1}).encode()):
        crafted.write_bytes(junk)
        sim = build()
        with sim, pytest.raises(CheckpointError, match=r"crafted\.ckpt"):
            sim.restore_state(crafted)


def test_an_old_pickle_checkpoint_loads_behind_unsafe(warm, tmp_path):
    path, _ = warm
    old = tmp_path / "old.ckpt"
    source = build()
    for _ in range(40):
        source.step_once()

    class Format1(pickle.Pickler):
        def persistent_id(self, obj):
            if obj is source:
                return ("sim",)
            if getattr(obj, "sim_core", None) is source and hasattr(obj, "object_id"):
                return ("object", obj.object_id)
            return None

    buffer = io.BytesIO()
    pickler = Format1(buffer)
    objects = [
        (o.object_id, f"{type(o).__module__}.{type(o).__qualname__}") for o in source.sim_objects
    ]
    pickler.dump(
        {"format": "fleet_async checkpoint", "version": 1, "timestep": 0.1, "objects": objects}
    )
    state = collect(source, source._checkpoint_parts())
    del state["streams"]  # format 1 had none
    pickler.dump(state)
    old.write_bytes(buffer.getvalue())
    source.close()
    sim = build()
    with sim, pytest.raises(CheckpointError, match="unsafe=True"):
        sim.restore_state(old)
    sim = build()
    sim.restore_state(old, unsafe=True)
    fresh = build()
    fresh.restore_state(path)
    assert digest(trace(sim, 30)) == digest(trace(fresh, 30))
    sim.close()
    fresh.close()


def test_save_refuses_state_that_is_not_plain_data_naming_it(tmp_path):
    sim = MultiRobotSimulationCore(SimulationParams(gui=False))
    robot = Agent.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")

    class Holds(AgentPlugin):
        def __init__(self, agent, config=None):
            super().__init__(agent, config)
            self.hook = lambda: None

    robot.add_plugin(Holds(robot))
    with (
        sim,
        pytest.raises(
            CheckpointError, match=r"plugin .*Holds\['hook'\]: .*lambda.* is not plain data"
        ),
    ):
        sim.save_state(tmp_path / "x.ckpt")
    assert not (tmp_path / "x.ckpt").exists()


def test_a_refused_restore_changes_nothing(warm):
    path, _ = warm
    sim = build()
    walker = next(a for a in sim.agents if a.name == "walker")
    assert walker.remove_controller(walker.controllers[-1])  # built differently: no walk
    before = _poses(sim)
    plugins_before = [p.get_state()["soc"] for a in sim.agents for p in a.plugins]
    names_before = [o.name for o in sim.sim_objects]
    with pytest.raises(CheckpointError, match=r"walker.*controllers has"):
        sim.restore_state(path)
    assert np.array_equal(_poses(sim), before)
    assert [p.get_state()["soc"] for a in sim.agents for p in a.plugins] == plugins_before
    assert [o.name for o in sim.sim_objects] == names_before
    assert sim.step_count == 0 and len(sim.attachments) == 0
    sim.close()


def test_a_file_that_does_not_exist_is_named(tmp_path):
    sim = build()
    with sim, pytest.raises(OSError, match="nowhere"):
        sim.restore_state(tmp_path / "nowhere.ckpt")
    assert os.path.exists(tmp_path)
