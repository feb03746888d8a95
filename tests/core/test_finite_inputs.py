"""NaN and infinities are refused by every public setter that takes numbers, one test per
family: poses, velocity commands, joint targets and tolerances, controller and spawn parameters,
batched poses, actions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fleet_async import (
    Agent,
    ControllerParams,
    JointAction,
    Pose,
    PoseAction,
    ShapeParams,
    WaitAction,
)

BAD = [math.nan, math.inf, -math.inf]
BOX = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def mobile(sim):
    return Agent.from_mesh(
        visual_shape=BOX, collision_shape=BOX, pose=Pose.from_xyz(0, 0, 0.1), sim_core=sim
    )


def arm(sim, **kwargs):
    return Agent.from_urdf("arm_robot", use_fixed_base=True, sim_core=sim, **kwargs)


@pytest.mark.parametrize("bad", BAD)
def test_poses(sim, bad):
    agent = mobile(sim)
    with pytest.raises(ValueError, match="finite"):
        agent.set_pose(Pose.from_xyz(bad, 0, 0))
    with pytest.raises(ValueError, match="finite"):
        agent.set_pose_raw([0, bad, 0], [0, 0, 0, 1])
    with pytest.raises(ValueError, match="finite"):
        sim.set_poses([agent.object_id], np.array([[0, 0, bad]]), np.array([[0, 0, 0, 1.0]]))
    assert np.isfinite(agent.get_pose().position).all()


@pytest.mark.parametrize("bad", BAD)
def test_velocity_commands(sim, bad):
    agent = mobile(sim)
    with pytest.raises(ValueError, match=r"set_cmd_vel\.wz: expected a finite number"):
        agent.set_cmd_vel(0.1, 0.0, bad)


@pytest.mark.parametrize("bad", BAD)
def test_joint_targets(sim, bad):
    robot = arm(sim)
    name = robot.joint_names[0]
    for call in (
        lambda: robot.set_joint_target(0, bad),
        lambda: robot.set_joint_target_by_name(name, bad),
        lambda: robot.set_joints_targets_by_name({name: bad}),
        lambda: robot.set_all_joints_targets([bad] * robot.get_num_joints()),
    ):
        with pytest.raises(ValueError, match=repr(bad).strip("'")):
            call()


@pytest.mark.parametrize("bad", BAD)
def test_joint_tolerances(sim, bad):
    robot = arm(sim)
    with pytest.raises(ValueError, match=rf"joint_tolerance: expected finite numbers >= 0.*{bad}"):
        robot.joint_tolerance = bad
    with pytest.raises(ValueError, match=r"joint_tolerance: expected finite numbers"):
        robot.joint_tolerance = {robot.joint_names[0]: bad}
    with pytest.raises(ValueError, match=r"Agent\.joint_tolerance: expected finite numbers"):
        arm(sim, joint_tolerance=[0.01, bad])
    with pytest.raises(ValueError, match=r"finite number >= 0"):
        robot.is_joint_at_target(0, 0.0, tolerance=bad)


@pytest.mark.parametrize("bad", BAD)
def test_end_effector_targets(sim, bad):
    robot = arm(sim)
    with pytest.raises(ValueError, match="finite"):
        robot.move_end_effector([0.3, bad, 0.3])
    with pytest.raises(ValueError, match=r"PoseAction\.target_position"):
        PoseAction(target_position=[0.3, 0.0, bad])


@pytest.mark.parametrize("bad", BAD)
def test_controller_and_spawn_parameters(sim, bad):
    if bad == math.inf:  # a limit of +inf is documented as "no limit" (motion/segments.py)
        assert ControllerParams(max_linear_vel=bad).max_linear_vel == math.inf
    else:
        with pytest.raises(ValueError, match=r"ControllerParams\.max_linear_vel"):
            ControllerParams(max_linear_vel=bad)
    with pytest.raises(ValueError, match=r"ControllerParams\.max_angular_vel"):
        ControllerParams(max_angular_vel=[1.0, 1.0, math.nan])
    with pytest.raises(ValueError, match=r"mass"):
        Agent.from_mesh(visual_shape=BOX, mass=bad, sim_core=sim)


@pytest.mark.parametrize("bad", BAD)
def test_actions(bad):
    with pytest.raises(ValueError, match=r"WaitAction\.duration"):
        WaitAction(duration=bad)
    with pytest.raises(ValueError, match=r"JointAction\.target_joint_positions: expected finite"):
        JointAction(target_joint_positions=[0.0, bad])
    with pytest.raises(ValueError, match=r"JointAction\.target_joint_positions: expected finite"):
        JointAction(target_joint_positions={"joint": bad})
