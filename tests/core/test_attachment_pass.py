"""The per-step attachment pass recomputes only the children whose parent or own row was
written since it last ran (the store's ``written`` flags); that must give, bit for bit, what
recomputing every child every step gives (``attachments.incremental = False``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimObject
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def _run(incremental: bool) -> list[bytes]:
    sim = MultiRobotSimulationCore(headless_params())
    try:
        sim.attachments.incremental = incremental
        robots = [
            Agent.from_mesh(
                visual_shape=BOX,
                collision_shape=BOX,
                pose=Pose.from_xyz(2.0 * i, 0.0, 0.1),
                sim_core=sim,
                controller={"type": "omni", "max_linear_vel": 1.0},
            )
            for i in range(4)
        ]
        totes = [
            SimObject.from_mesh(BOX, BOX, Pose.from_xyz(2.0 * i, 0.0, 0.3), sim_core=sim)
            for i in range(4)
        ]
        for robot, tote in zip(robots, totes, strict=True):
            robot.attach_object(tote, relative_pose=Pose.from_euler(0.1, 0.0, 0.2, yaw=0.3))
        cup = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(0.0, 0.0, 0.5), sim_core=sim)
        totes[0].attach_object(cup, relative_pose=Pose.from_xyz(0.0, 0.05, 0.2))
        robots[0].set_path([Pose.from_xyz(3.0, 1.0, 0.1), Pose.from_euler(0, 2, 0.1, yaw=2.0)])
        robots[2].set_goal_pose(Pose.from_euler(4.0, -1.0, 0.1, yaw=-1.0))
        frames = []
        for step in range(60):
            if step == 10:  # a carrier moved between steps, and one carried object by hand
                robots[1].set_pose(Pose.from_euler(2.5, 0.5, 0.1, yaw=math.pi / 3))
                totes[3].set_pose(Pose.from_xyz(9.0, 9.0, 9.0))
            if step == 20:  # a pose written with the value it had: flagged, unchanged
                robots[3].set_pose(robots[3].get_pose())
            if step == 30:
                robots[1].set_goal_pose(Pose.from_xyz(0.0, 3.0, 0.1))
            sim.step_once()
            store = sim.state
            frames.append(
                store.position[: store.high_water].tobytes()
                + store.orientation[: store.high_water].tobytes()
            )
        assert np.allclose(totes[3].get_pose().position, [6.0 + 0.1, 0.0, 0.3])
        assert cup.get_pose().position.tolist() != [0.0, 0.0, 0.5]
        return frames
    finally:
        sim.close()


def test_flagged_pass_gives_the_full_pass_bits_at_every_step():
    flagged, full = _run(incremental=True), _run(incremental=False)
    assert len(flagged) == len(full) == 60
    for step, (a, b) in enumerate(zip(flagged, full, strict=True)):
        assert a == b, step


def test_only_written_rows_are_recomputed():
    sim = MultiRobotSimulationCore(headless_params())
    try:
        carrier = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(0.0, 0.0, 0.1), sim_core=sim)
        tote = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(0.0, 0.0, 0.3), sim_core=sim)
        carrier.attach_object(tote, relative_pose=Pose.from_xyz(0.0, 0.0, 0.2))
        sim.step_once()
        store = sim.state
        assert not store.written[: store.high_water].any()  # the pass cleared its flags
        carrier.set_pose(Pose.from_xyz(1.0, 0.0, 0.1))
        assert store.written[carrier.state_row] and store.written[tote.state_row]
        sim.step_once()
        assert tote.get_pose().position.tolist() == [1.0, 0.0, 0.30000000000000004]
        assert not store.written[: store.high_water].any()
    finally:
        sim.close()


def _carriers(incremental: bool, kernels: str) -> list[bytes]:
    """60 carriers, differential and omni, turned at random, each with a tote on a turned
    relative pose, driving seeded paths (turning and driving straight, some at once)."""
    sim = MultiRobotSimulationCore(headless_params(enable_floor=False, kernels=kernels))
    rng = np.random.default_rng(3)
    body = ShapeParams("box", half_extents=[0.2, 0.15, 0.1])
    tote = ShapeParams("box", half_extents=[0.1, 0.1, 0.05])
    frames = []
    with sim:
        sim.attachments.incremental = incremental
        robots = []
        for i in range(60):
            yaw = float(rng.uniform(-3, 3))
            robot = Agent.from_mesh(
                visual_shape=None,
                collision_shape=body,
                pose=Pose.from_euler(2.0 * (i % 8), 2.0 * (i // 8), 0.1, 0.0, 0.0, yaw),
                sim_core=sim,
                controller={"type": "differential" if i % 2 else "omni"},
            )
            box = SimObject.from_mesh(tote, tote, Pose.from_xyz(0, 0, 0.3), sim_core=sim)
            robot.attach_object(box, relative_pose=Pose.from_euler(0.1, 0.05, 0.15, 0.1, 0, 0.4))
            robots.append(robot)
        for step in range(150):
            if step % 25 == 0:
                for robot in robots:
                    x, y, _ = robot.get_pose().position.tolist()
                    dx, dy = rng.uniform(-3, 3, 2)
                    yaw = float(rng.uniform(-3, 3))
                    robot.set_path([Pose.from_euler(x + dx, y + dy, 0.1, 0.0, 0.0, yaw)])
            sim.step_once()
            frames.append(sim.state.position.tobytes() + sim.state.orientation.tobytes())
    return frames


@pytest.mark.parametrize("kernels", ["numpy", "numba"])
def test_turning_and_driving_carriers_give_the_full_pass_bits(kernels):
    """Kept frames (a parent that kept its orientation's bits) and the compiled advance (which
    must flag what it writes) against composing every child every step."""
    assert _carriers(True, kernels) == _carriers(False, kernels)
