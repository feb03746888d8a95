"""Checkpoints keep the safety fields: each robot's field parameters, its stopped state, the
KPI counters and the deadlock watch; the restored run continues step for step identically."""

from __future__ import annotations

import json

import numpy as np
import pytest

from fleet_async import CheckpointError, Pose, SimEvents
from fleet_async.core.checkpoint.saving import collect
from tests.core.traffic.test_safety_fields import make_sim, robot, wall


def build():
    """Two robots head-on (they stop and deadlock), one held by a wall, one with other
    fields driving free, one without fields; deadlocks suspected after 2 s."""
    sim = make_sim()
    sim.safety.deadlock_after = 2.0
    a = robot(sim, 0.0, name="a")
    b = robot(sim, 3.0, name="b", yaw=np.pi)
    c = robot(sim, 0.0, 3.0, name="c", fields={"deceleration": 2.0, "protective_margin": 0.3})
    d = robot(sim, 0.0, 6.0, name="d", fields={"slow_factor": 0.3, "footprint": [0.8, 0.5]})
    e = robot(sim, 0.0, -3.0, name="e", fields=None)
    wall(sim, 3.0, 3.0)
    a.set_path([Pose.from_xyz(5.0, 0.0, 0.2)])
    b.set_path([Pose.from_xyz(-2.0, 0.0, 0.2)])
    c.set_path([Pose.from_xyz(5.0, 3.0, 0.2)])
    d.set_path([Pose.from_xyz(8.0, 6.0, 0.2)])
    e.set_cmd_vel(vx=0.5)
    return sim


def run(sim, steps):
    """Every robot's pose each step and every safety event, with its step."""
    log = []
    for kind in (
        SimEvents.SAFETY_STOP_STARTED,
        SimEvents.SAFETY_STOP_ENDED,
        SimEvents.DEADLOCK_SUSPECTED,
    ):
        sim.events.on(
            kind,
            lambda k=kind, **p: log.append(
                (k, sim.step_count, p["agent"].name if "agent" in p else None)
            ),
        )
    poses = []
    for _ in range(steps):
        sim.step_once()
        poses.append(np.array([a.get_pose().position for a in sim.agents]))
    return np.array(poses), log, sim.safety.stats(), sim.safety.deadlocks_suspected


def test_a_restored_run_continues_with_the_same_stops_and_counters(tmp_path):
    path = tmp_path / "fields.ckpt"
    with build() as sim:
        for _ in range(16):
            sim.step_once()
        a, b = (next(x for x in sim.agents if x.name == n) for n in "ab")
        assert sim.safety.is_stopped(a) and sim.safety.is_stopped(b)
        assert sim.safety.deadlocks_suspected == 0
        sim.save_state(path)
        before = sim.safety.stats()
        expected = run(sim, 40)
    with build() as fresh:
        fresh.restore_state(path)
        a, b, d = (next(x for x in fresh.agents if x.name == n) for n in "abd")
        assert fresh.safety.is_stopped(a) and fresh.safety.is_stopped(b)
        assert fresh.safety.stats() == before
        assert fresh.safety.params_of(d).slow_factor == 0.3
        assert fresh.safety.params_of(d).footprint == (0.8, 0.5)
        got = run(fresh, 40)
    assert expected[3] == 1  # the head-on pair was suspected after the restore point ...
    np.testing.assert_array_equal(got[0], expected[0])
    assert got[1:] == expected[1:]  # ... in both runs, at the same step, with the same stops


def test_fields_given_after_the_scenario_was_built_come_back(tmp_path):
    path = tmp_path / "late.ckpt"
    with build() as sim:
        e = next(x for x in sim.agents if x.name == "e")
        sim.safety.enable(e, {"deceleration": 3.0})
        sim.safety.disable(next(x for x in sim.agents if x.name == "d"))
        for _ in range(5):
            sim.step_once()
        sim.save_state(path)
        assert json.dumps(collect(sim, sim._checkpoint_parts())["safety"]["watch"])
    with build() as fresh:
        fresh.restore_state(path)
        e, d = (next(x for x in fresh.agents if x.name == n) for n in "ed")
        assert fresh.safety.params_of(e).deceleration == 3.0
        assert fresh.safety.params_of(d) is None
        assert d.object_id in fresh.safety.stats()  # a robot that lost its fields keeps its count


def test_a_checkpoint_with_bad_field_settings_is_refused_and_changes_nothing(tmp_path, monkeypatch):
    path = tmp_path / "bad.ckpt"
    with build() as sim:
        sim.step_once()
        real = sim.safety.get_state

        def damaged():
            state = real()
            state["table"]["agents"][0]["params"]["deceleration"] = -1.0
            return state

        monkeypatch.setattr(sim.safety, "get_state", damaged)
        sim.save_state(path)
    with build() as fresh:
        a = next(x for x in fresh.agents if x.name == "a")
        with pytest.raises(CheckpointError, match="deceleration"):
            fresh.restore_state(path)
        assert fresh.safety.params_of(a).deceleration == 1.0
        assert fresh.step_count == 0
