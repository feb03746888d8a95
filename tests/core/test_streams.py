"""Random streams: one generator per user, from (seed, key); reseeding re-derives them all."""

from __future__ import annotations

import numpy as np
import pytest

from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimulationParams

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def _sim(seed: int = 3) -> MultiRobotSimulationCore:
    return MultiRobotSimulationCore(SimulationParams(gui=False, seed=seed))


def test_a_stream_is_seeded_from_seed_and_key():
    with _sim() as sim:
        robot = Agent.from_mesh(BOX, BOX, Pose.from_xyz(0, 0, 0.1), sim_core=sim)
        stream = sim.rng_for(robot, "battery")
        assert sim.rng_for(robot, "battery") is stream  # the same key, the same generator
        expected = np.random.default_rng(sim.seed_sequence(robot.object_id, "battery"))
        assert stream.uniform() == expected.uniform()
        assert sim.rng_for(robot, "other").uniform() != sim.rng_for(robot, "battery").uniform()
        # the random walk's stream is the one it always had: default_rng([seed, id, 0x5A17])
        walk = np.random.default_rng([3, robot.object_id, 0x5A17]).uniform()
        assert sim.rng_for(robot, 0x5A17).uniform() == walk
        with pytest.raises(ValueError, match=r"key part -1"):
            sim.rng_for(-1)


def test_reseed_rederives_every_stream_in_place():
    with _sim(seed=3) as sim, _sim(seed=9) as other:
        held = sim.rng_for(4, 2)
        held.uniform(size=5)
        sim.rng.uniform(size=5)
        sim.reseed(9)
        assert held is sim.rng_for(4, 2)
        assert held.uniform() == other.rng_for(4, 2).uniform()
        assert sim.rng.uniform() == other.rng.uniform()
        with pytest.raises(ValueError, match=r"sim.reseed: seed: expected an int >= 0"):
            sim.reseed(-2)


def test_reset_starts_the_streams_over():
    with _sim(seed=3) as sim:
        first = sim.rng_for(1).uniform()
        sim.reset(seed=3)
        assert sim.rng_for(1).uniform() == first
