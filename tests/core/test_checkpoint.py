"""Checkpoints: a restored simulation continues step for step as the original did."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import fleet_async as fa
from fleet_async import (
    Agent,
    AgentPlugin,
    CheckpointError,
    MoveAction,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimObject,
    SimulationParams,
    load_yaml_config,
)
from tests.core.checkpoint_scene import build, digest, trace

SCENE = Path(__file__).with_name("checkpoint_scene.py")
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    """The scene run 83 steps (the crate is on its way), saved, then run 150 more."""
    path = tmp_path_factory.mktemp("checkpoint") / "warm.ckpt"
    sim = build()
    for _ in range(83):
        sim.step_once()
    assert sim.attachments.of_child(sim.sim_objects[4]) is not None  # the crate is carried
    sim.save_state(path)
    result = trace(sim, 150)
    sim.close()
    kinds = {event[1] for event in result["events"]}
    assert {"action_completed", "collision_started"} <= kinds  # the trace has something in it
    return path, result


def test_restore_continues_step_for_step(saved):
    path, original = saved
    sim = build()
    sim.restore_state(path)
    assert (sim.step_count, sim.sim_time) == (83, pytest.approx(8.3))
    restored = trace(sim, 150)
    sim.close()
    assert np.array_equal(restored["poses"], original["poses"])
    assert restored["events"] == original["events"]
    assert restored["soc"] == original["soc"] and restored["rng"] == original["rng"]
    assert (restored["step"], restored["collisions"]) == (original["step"], original["collisions"])


def test_restore_in_a_fresh_process(saved):
    path, original = saved
    env = dict(os.environ)
    root = str(SCENE.parents[2])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    result = subprocess.run(
        [sys.executable, str(SCENE), "restore", str(path), "150"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == digest(original)


def test_many_runs_branch_from_one_checkpoint(saved):
    path, original = saved
    branches = []
    for seed in (1, 2):
        sim = build()
        sim.restore_state(path)
        sim.rng = np.random.default_rng(seed)  # each branch draws its own errands from here
        branches.append(trace(sim, 100)["poses"])
        sim.close()
    assert np.array_equal(branches[0][0], original["poses"][0])  # the same first step
    assert not np.array_equal(branches[0], branches[1])


def test_missions_start_from_a_restored_state(tmp_path):
    def scene() -> tuple[MultiRobotSimulationCore, Agent]:
        sim = MultiRobotSimulationCore(SimulationParams(gui=False, target_rtf=0.0, timestep=0.1))
        robot = Agent.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")
        return sim, robot

    def shift(sim: MultiRobotSimulationCore, robot: Agent) -> tuple[float, list[float]]:
        async def main() -> None:
            await robot.move(Pose.from_xyz(0.0, 3.0, 0.1))
            await sim.sleep(1.0)

        fa.run(sim, main)
        return sim.sim_time, robot.get_pose().position.tolist()

    original, robot = scene()
    robot.add_action(MoveAction(path=Pose.from_xyz(4.0, 0.0, 0.1)))
    for _ in range(12):  # the first move is under way
        original.step_once()
    original.save_state(tmp_path / "warm.ckpt")
    expected = shift(original, robot)
    original.close()
    restored, robot2 = scene()
    with restored:
        restored.restore_state(tmp_path / "warm.ckpt")
        assert shift(restored, robot2) == expected


def test_refuses_physics_running_missions_and_object_callbacks(sim, tmp_path):
    path = tmp_path / "x.ckpt"
    physics = MultiRobotSimulationCore(SimulationParams(gui=False, physics=True))
    with physics, pytest.raises(CheckpointError, match="physics=True"):
        physics.save_state(path)

    async def main() -> None:
        sim.save_state(path)

    with pytest.raises(CheckpointError, match="missions are running"):
        fa.run(sim, main)  # a lone mission error is raised as itself
    box = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim)
    box.register_callback(lambda *args: None, frequency=1.0)
    with pytest.raises(CheckpointError, match="per-object callbacks"):
        sim.save_state(path)
    assert not path.exists()


def test_refuses_devices_and_other_added_motion_systems(sim, tmp_path):
    path = tmp_path / "x.ckpt"
    fa.Door.from_dict({"name": "d", "pose": [2.0, 0.0, 0.0], "open_time": 1.0}, sim)
    with pytest.raises(CheckpointError, match=r"DeviceMotion \(added with sim.add_motion_system"):
        sim.save_state(path)
    assert not path.exists()


def test_refuses_a_target_built_differently_or_already_stepped(saved):
    path, _ = saved
    stepped = build()
    stepped.step_once()
    with pytest.raises(CheckpointError, match="has run 1 steps"):
        stepped.restore_state(path)
    stepped.close()
    other = build()
    SimObject.from_mesh(BOX, BOX, Pose.from_xyz(9, 9, 0.1), sim_core=other)
    with pytest.raises(CheckpointError, match="other objects than the checkpoint"):
        other.restore_state(path)
    other.close()
    finer = MultiRobotSimulationCore(SimulationParams(gui=False, timestep=0.05))
    with finer, pytest.raises(CheckpointError, match=r"timestep is 0\.1 s"):
        finer.restore_state(path)


def test_refuses_a_file_that_is_no_checkpoint(sim, tmp_path):
    junk = tmp_path / "junk.ckpt"
    junk.write_bytes(b"not a pickle")
    with pytest.raises(CheckpointError, match="not a readable checkpoint"):
        sim.restore_state(junk)


def test_unpicklable_state_names_the_way_out(sim, tmp_path):
    robot = Agent.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim, controller="omni")

    class Holds(AgentPlugin):
        def __init__(self, agent, config=None):
            super().__init__(agent, config)
            self.hook = lambda: None

    robot.add_plugin(Holds(robot))
    with pytest.raises(CheckpointError, match="get_state / set_state"):
        sim.save_state(tmp_path / "x.ckpt")


def test_a_yaml_scenario_with_urdf_robots_restores(tmp_path):
    scenario = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "pick_drop.yaml"

    def load() -> MultiRobotSimulationCore:
        config = load_yaml_config(scenario)
        config["simulation"].update(gui=False, target_rtf=0.0)
        return MultiRobotSimulationCore.from_dict(config, base_dir=scenario.parent)

    original = load()
    for _ in range(120):  # the robots carry their boxes
        original.step_once()
    assert len(original.attachments) == 3
    original.save_state(tmp_path / "pick.ckpt")
    expected = trace(original, 150)
    original.close()
    restored = load()
    restored.restore_state(tmp_path / "pick.ckpt")
    got = trace(restored, 150)
    restored.close()
    assert np.array_equal(got["poses"], expected["poses"]) and got["events"] == expected["events"]
