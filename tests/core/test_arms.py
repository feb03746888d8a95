"""Arms: joint state and targets, kinematic joint speed, tolerances, IK, JointAction / PoseAction,
arm pick and drop, and the manager's bulk joint helper."""

from __future__ import annotations

import logging
import math

import numpy as np
import pybullet as p
import pytest

from fleet_async import (
    ActionStatus,
    Agent,
    AgentManager,
    DropAction,
    IKParams,
    JointAction,
    MultiRobotSimulationCore,
    PickAction,
    Pose,
    PoseAction,
    ShapeParams,
    SimEvents,
    SimObject,
)
from tests.conftest import headless_params

ARM_JOINTS = ["base_to_shoulder", "shoulder_to_elbow", "elbow_to_wrist", "wrist_to_end"]
CUBE = ShapeParams("box", half_extents=[0.03, 0.03, 0.03])


def arm(sim, **kwargs):
    return Agent.from_urdf("arm_robot", use_fixed_base=True, sim_core=sim, **kwargs)


def cube(sim, xyz):
    return SimObject.from_mesh(CUBE, CUBE, Pose(list(xyz)), sim_core=sim)


def run_until(sim, action, limit=400):
    for _ in range(limit):
        if action.is_complete():
            return
        sim.step_once()
    raise AssertionError(f"{action!r} did not finish in {limit} steps")


URDF_NO_LIMITS = """<?xml version="1.0"?>
<robot name="slider">
  <link name="base"><inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0"
    iyz="0" izz="0"/></inertial></link>
  <link name="a"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4"
    iyz="0" izz="1e-4"/></inertial></link>
  <link name="b"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4"
    iyz="0" izz="1e-4"/></inertial></link>
  <joint name="spin" type="continuous"><parent link="base"/><child link="a"/>
    <axis xyz="0 0 1"/></joint>
  <joint name="slide" type="prismatic"><parent link="a"/><child link="b"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="0"/></joint>
</robot>
"""


# ----- joint state and targets -------------------------------------------------------------


def test_joint_introspection(sim):
    a = arm(sim)
    assert a.get_num_joints() == 4
    assert a.joint_names == ARM_JOINTS
    assert a.get_all_joints_state() == [(0.0, 0.0)] * 4
    assert a.get_all_joints_state_by_name() == dict.fromkeys(ARM_JOINTS, (0.0, 0.0))
    assert a.get_joints_state_by_name(["elbow_to_wrist"]) == {"elbow_to_wrist": (0.0, 0.0)}
    box = Agent.from_mesh(CUBE, CUBE, Pose([3, 0, 0.1]), sim_core=sim)
    assert box.get_num_joints() == 0 and box.joint_names == []
    with pytest.raises(ValueError, match="has no joints"):
        box.set_joint_target(0, 1.0)


def test_kinematic_joint_moves_at_the_urdf_velocity_limit_and_lands_exactly(sim):
    a = arm(sim)  # every arm joint: velocity="1.5" rad/s; dt = 0.1 s -> 0.15 rad per step
    a.set_joint_target(0, 1.0)
    a.set_joint_target_by_name("shoulder_to_elbow", -0.3)
    seen = []
    for _ in range(8):
        sim.step_once()
        seen.append(a.get_joint_state(0))
    assert [round(pos, 9) for pos, _ in seen[:6]] == [0.15, 0.3, 0.45, 0.6, 0.75, 0.9]
    assert seen[0][1] == pytest.approx(1.5)
    assert seen[6] == (1.0, 0.0) and seen[7] == (1.0, 0.0)  # arrived exactly, at rest
    assert a.get_joint_state_by_name("shoulder_to_elbow")[0] == -0.3  # two steps: 0.15 + 0.15
    # PyBullet's forward kinematics follows: the link's pose matches the joint angle.
    link_orn = p.getLinkState(a.body_id, 0, physicsClientId=sim.client)[5]
    assert p.getEulerFromQuaternion(link_orn)[2] == pytest.approx(1.0)


def test_prismatic_and_fallback_velocities(sim, tmp_path):
    urdf = tmp_path / "slider.urdf"
    urdf.write_text(URDF_NO_LIMITS)
    s = Agent.from_urdf(str(urdf), use_fixed_base=True, sim_core=sim)
    assert s.joints.max_velocity.tolist() == [
        Agent._KINEMATIC_JOINT_FALLBACK_VELOCITY,
        Agent._KINEMATIC_PRISMATIC_FALLBACK_VELOCITY,
    ]
    s.set_joints_targets({"spin": 10.0, "slide": 0.8})  # continuous: no limit to clamp to
    sim.step_once()
    assert s.get_joint_state(0)[0] == pytest.approx(0.2)  # 2.0 rad/s * 0.1 s
    assert s.get_joint_state(1)[0] == pytest.approx(0.05)  # 0.5 m/s * 0.1 s
    mm = Agent.from_urdf("mobile_manipulator", pose=Pose([5, 0, 0.15]), sim_core=sim)
    mm.set_joint_target_by_name("rail_joint", 0.3)  # URDF velocity 0.2 m/s -> 0.02 m/step
    for _ in range(3):
        sim.step_once()
    assert mm.get_joint_state_by_name("rail_joint")[0] == pytest.approx(0.06)


def test_targets_outside_limits_are_clamped_with_a_warning(sim, caplog):
    a = arm(sim)  # limits +-2.9 rad
    with caplog.at_level(logging.WARNING):
        a.set_joint_target(1, 4.0)
    assert "outside its limits" in caplog.text and "shoulder_to_elbow" in caplog.text
    assert a.joints.targets[1] == 2.9
    for _ in range(30):
        sim.step_once()
    assert a.get_joint_state(1)[0] == 2.9


def test_bad_joint_commands_say_what_is_wrong(sim):
    a = arm(sim)
    with pytest.raises(ValueError, match=r"no joint named 'elbow'.*base_to_shoulder"):
        a.set_joint_target_by_name("elbow", 1.0)
    with pytest.raises(ValueError, match=r"joint index 4 out of range \[0, 4\)"):
        a.set_joint_target(4, 1.0)
    with pytest.raises(ValueError, match=r"expected 4 joint targets.*got 3"):
        a.set_all_joints_targets([0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match="must be a number"):
        a.set_joint_target(0, "up")
    panda = Agent.from_urdf("panda", pose=Pose([2, 0, 0]), use_fixed_base=True, sim_core=sim)
    with pytest.raises(ValueError, match=r"'panda_joint8'.*is fixed"):
        panda.set_joint_target_by_name("panda_joint8", 0.1)


def test_list_targets_per_joint_or_per_movable_joint(sim):
    panda = Agent.from_urdf("panda", use_fixed_base=True, sim_core=sim)
    assert panda.get_num_joints() == 12 and len(panda.joints.movable_indices) == 9
    panda.set_all_joints_targets([0.1] * 9)  # one per movable joint
    assert np.isnan(panda.joints.targets[7]) and panda.joints.targets[9] == pytest.approx(0.04)
    panda.set_joints_targets([0.2] * 12)  # one per joint; fixed joints' entries ignored
    assert panda.joints.targets[0] == 0.2 and np.isnan(panda.joints.targets[8])


# ----- tolerances --------------------------------------------------------------------------


def test_tolerance_resolution_rules(sim):
    a = arm(sim, joint_tolerance={"elbow_to_wrist": 0.2})
    a.joints.set_positions({0: 0.05, 2: 0.15})
    # Agent default is a dict: named joints use it, the others the class default 0.01.
    assert a.resolve_joint_tolerance(None, "elbow_to_wrist") == 0.2
    assert a.resolve_joint_tolerance(None, 0) == 0.01
    assert a.is_joint_at_target_by_name("elbow_to_wrist", 0.0)
    assert not a.is_joint_at_target(0, 0.0)
    assert a.is_joint_at_target(0, 0.0, tolerance=0.06)
    assert a.is_joint_at_target(0, 0.0, tolerance=[0.06, 0, 0, 0])
    assert not a.are_joints_at_targets([0.0] * 4, tolerance=0.1)
    assert a.are_joints_at_targets([0.0] * 4, tolerance=[0.06, 0.0, 0.16, 0.0])
    assert (
        a.are_joints_at_targets_by_name(
            {"base_to_shoulder": 0.0, "elbow_to_wrist": 0.0}, tolerance={"base_to_shoulder": 0.06}
        )
        is False
    )  # elbow falls back to 0.01
    assert a.are_all_joints_at_targets([0.05, 0.0, 0.15, 0.0])
    with pytest.raises(ValueError, match="tolerance list has 1 entries, none for joint index 2"):
        a.is_joint_at_target(2, 0.0, tolerance=[0.1])
    a.joint_tolerance = 0.5
    assert a.are_joints_at_targets([0.0] * 4)


def test_no_targets_means_last_commanded_ones(sim):
    a = arm(sim)
    assert a.are_joints_at_targets() and a.are_all_joints_at_targets()  # nothing commanded
    a.set_joint_target(3, 0.6)
    assert not a.are_joints_at_targets()
    for _ in range(4):
        sim.step_once()
    assert a.are_joints_at_targets() and a.are_all_joints_at_targets()


# ----- JointAction -------------------------------------------------------------------------


def test_joint_action_completes_at_the_exact_step_and_writes_back_its_tolerance(sim):
    a = arm(sim, joint_tolerance=0.02)
    action = JointAction(target_joint_positions=[0.9, 0.0, 0.0, 0.0])
    a.add_action(action)
    run_until(sim, action)
    assert action.status is ActionStatus.COMPLETED
    assert action.tolerance == 0.02
    # 0.9 rad at 0.15 rad/step: within 0.02 after the 6th step (t = 0.6 s).
    assert action.start_time == 0.0 and action.end_time == pytest.approx(0.6)
    assert sim.step_count == 6


def test_joint_action_dict_targets_with_per_joint_tolerance(sim):
    mm = Agent.from_urdf("mobile_manipulator", pose=Pose([0, 0, 0.15]), sim_core=sim)
    action = JointAction(
        target_joint_positions={"rail_joint": 0.1, "elbow_to_wrist": -0.3},
        tolerance={"rail_joint": 0.005, "elbow_to_wrist": 0.1},
    )
    mm.add_action(action)
    run_until(sim, action)
    # rail: 0.1 m at 0.02 m/step -> within 5 mm after step 5 (0.1 m reached exactly).
    assert action.end_time == pytest.approx(0.5)
    assert mm.get_joint_state_by_name("rail_joint")[0] == pytest.approx(0.1)


def test_joint_action_fails_with_a_reason(sim):
    box = Agent.from_mesh(CUBE, CUBE, Pose([0, 0, 0.1]), sim_core=sim)
    action = JointAction(target_joint_positions=[1.0])
    box.add_action(action)
    run_until(sim, action)
    assert action.status is ActionStatus.FAILED and "has no joints" in action.error_message
    a = arm(sim)
    bad = JointAction(target_joint_positions={"nope": 1.0})
    a.add_action(bad)
    run_until(sim, bad)
    assert bad.status is ActionStatus.FAILED and "no joint named 'nope'" in bad.error_message
    with pytest.raises(ValueError, match="target_joint_positions"):
        JointAction(target_joint_positions=[])


def test_removing_an_arm_cancels_its_joint_action(sim):
    a = arm(sim)
    action = JointAction(target_joint_positions=[2.0, 0, 0, 0])
    a.add_action(action)
    sim.step_once()
    sim.remove_object(a)
    assert action.status is ActionStatus.CANCELLED
    assert len(sim.joint_motion) == 0
    sim.step_once()


# ----- IK ----------------------------------------------------------------------------------


def test_end_effector_auto_detection(sim):
    assert arm(sim).resolve_end_effector() == 3  # link "end_effector"
    panda = Agent.from_urdf("panda", pose=Pose([2, 0, 0]), use_fixed_base=True, sim_core=sim)
    assert panda.resolve_end_effector() == 11  # panda_grasptarget
    kuka = Agent.from_urdf("kuka_iiwa", pose=Pose([4, 0, 0]), use_fixed_base=True, sim_core=sim)
    assert kuka.resolve_end_effector() == 6  # end of the longest movable chain
    assert kuka.resolve_end_effector("lbr_iiwa_link_3") == 2
    with pytest.raises(ValueError, match="not the base"):
        kuka.resolve_end_effector(-1)


@pytest.mark.parametrize("target", [[0.3, 0.0, 0.5], [0.2, 0.2, 0.3], [-0.25, 0.1, 0.6]])
def test_reachable_targets_are_reached_within_tolerance(sim, target):
    a = arm(sim)
    assert a.move_end_effector(target) is True
    solution = a.ik_reach(target)
    assert solution.position_error <= a.ik_params.reachability_tolerance
    for _ in range(50):
        sim.step_once()
    pos, _ = a.get_end_effector_pose()
    assert np.linalg.norm(pos - target) <= 0.02
    assert a.are_ee_at_target(target)
    assert not a.are_ee_at_target(np.add(target, [0.1, 0, 0]))


def test_unreachable_target_reports_false_but_sets_best_effort_targets(sim):
    a = arm(sim)  # reach: 0.63 m beyond the shoulder pitch axis
    assert a.move_end_effector([3.0, 0.0, 0.3]) is False
    for _ in range(50):
        sim.step_once()
    pos, _ = a.get_end_effector_pose()
    assert pos[0] > 0.45  # stretched out towards the target
    assert np.linalg.norm(pos - [3.0, 0.0, 0.3]) > 2.0
    # The search leaves PyBullet's joints where the agent's are.
    assert [p.getJointState(a.body_id, j, physicsClientId=sim.client)[0] for j in range(4)] == (
        pytest.approx([s[0] for s in a.get_all_joints_state()])
    )


def test_orientation_targets_and_checks(sim):
    kuka = Agent.from_urdf("kuka_iiwa", use_fixed_base=True, sim_core=sim)
    down = p.getQuaternionFromEuler([math.pi, 0, 0])
    assert kuka.move_end_effector([0.5, 0.2, 0.6], down) is True
    for _ in range(60):
        sim.step_once()
    assert kuka.are_ee_at_target([0.5, 0.2, 0.6], down)
    assert not kuka.are_ee_at_target([0.5, 0.2, 0.6], [0, 0, 0, 1], orientation_tolerance=0.05)


def test_ik_joint_names_lock_the_other_joints(sim):
    mm_arm = ["mount_to_shoulder", "shoulder_to_elbow", "elbow_to_wrist", "wrist_to_end"]
    params = IKParams(ik_joint_names=mm_arm)  # rail locked
    mm = Agent.from_urdf(
        "mobile_manipulator", pose=Pose([0, 0, 0.15]), sim_core=sim, ik_params=params
    )
    solution = mm.ik_reach([0.5, 0.2, 0.5])
    rail = mm.joint_names.index("rail_joint")
    assert rail not in solution.targets
    assert set(solution.targets) == {mm.joint_names.index(n) for n in mm_arm}
    free = Agent.from_urdf("mobile_manipulator", pose=Pose([5, 0, 0.15]), sim_core=sim)
    auto = free.ik_reach([5.5, 0.2, 0.5])  # automatic: wheels (continuous) locked
    wheels = {free.joint_names.index(n) for n in ("left_wheel_joint", "right_wheel_joint")}
    assert not wheels & set(auto.targets) and rail in auto.targets
    with pytest.raises(ValueError, match="no joint named 'elbow'"):
        Agent.from_urdf(
            "mobile_manipulator", sim_core=sim, ik_params=IKParams(ik_joint_names=("elbow",))
        ).ik_reach([0.5, 0, 0.5])


def test_ik_works_from_the_agents_current_base_pose(sim):
    mm = Agent.from_urdf("mobile_manipulator", pose=Pose([0, 0, 0.15]), sim_core=sim)
    mm.set_pose(Pose.from_euler(4.0, 2.0, 0.15, yaw=math.pi / 2))  # store only, synced lazily
    assert mm.move_end_effector([4.0, 2.3, 0.8]) is True  # 0.3 m ahead of the base
    for _ in range(60):
        sim.step_once()
    assert mm.are_ee_at_target([4.0, 2.3, 0.8])


# ----- PoseAction --------------------------------------------------------------------------


def test_pose_action_completes_when_reached_and_fails_when_not(sim):
    a = arm(sim)
    ok = PoseAction(target_position=[0.3, 0.1, 0.4])
    far = PoseAction(target_position=[0.0, 2.0, 0.4])
    a.add_action_sequence([ok, far])
    run_until(sim, far)
    assert ok.status is ActionStatus.COMPLETED and ok.reachable is True
    assert far.status is ActionStatus.FAILED and far.reachable is False
    assert "unreachable" in far.error_message and "m from it" in far.error_message
    assert ok.end_time < far.start_time + 1e-9
    with pytest.raises(ValueError, match="target_position"):
        PoseAction(target_position=[1, 2])
    with pytest.raises(ValueError, match="tolerance"):
        PoseAction(target_position=[1, 2, 3], tolerance=0)


# ----- pick and drop with an arm -----------------------------------------------------------


def test_fixed_arm_picks_and_drops_and_the_object_follows_the_link_every_step(sim):
    a = arm(sim)
    box = cube(sim, [0.45, 0.0, 0.05])
    rel = Pose([0.0, 0.0, 0.0])
    pick = PickAction(
        target_object_id=box.body_id,
        ee_target_position=[0.45, 0.0, 0.1],
        attach_link="end_effector",
        attach_relative_pose=rel,
    )
    drop = DropAction(drop_pose=Pose([0.0, 0.45, 0.05]), ee_target_position=[0.0, 0.45, 0.1])
    a.add_action_sequence([pick, drop])
    gaps = []

    def check(**_):
        if box.is_attached():
            link_pos, _ = sim.world.link_pose(a, 3)
            gaps.append(float(np.linalg.norm(box.get_pose().position - link_pos)))

    sim.events.on(SimEvents.POST_STEP, check)
    run_until(sim, drop)
    assert pick.status is ActionStatus.COMPLETED and drop.status is ActionStatus.COMPLETED
    assert len(gaps) > 10 and max(gaps) < 1e-9  # glued to the link in every step carried
    assert box.get_pose().position.tolist() == pytest.approx([0.0, 0.45, 0.05])
    assert not box.is_attached()
    assert a.are_ee_at_target([0.0, 0.45, 0.1])  # the arm stays where the drop's reach took it


def test_ik_failure_fails_the_pick_unless_told_to_continue(sim):
    a = arm(sim)
    box = cube(sim, [2.0, 0.0, 0.05])
    strict = PickAction(
        target_object_id=box.body_id,
        ee_target_position=[2.0, 0.0, 0.1],
        continue_on_ik_failure=False,
    )
    a.add_action(strict)
    run_until(sim, strict)
    assert strict.status is ActionStatus.FAILED and "out of reach" in strict.error_message
    assert not box.is_attached()
    lenient = PickAction(target_object_id=box.body_id, ee_target_position=[2.0, 0.0, 0.1])
    a.add_action(lenient)
    run_until(sim, lenient)
    assert lenient.status is ActionStatus.COMPLETED and box.get_attached_parent() is a


def test_pick_with_joint_targets(sim):
    a = arm(sim)
    box = cube(sim, [0.5, 0.0, 0.2])
    pick = PickAction(
        target_object_id=box,
        joint_targets={"shoulder_to_elbow": 1.0},
        joint_tolerance=0.001,
        attach_link="end_effector",
    )
    a.add_action(pick)
    run_until(sim, pick)
    assert pick.status is ActionStatus.COMPLETED and box.get_attached_parent() is a
    assert a.get_joint_state_by_name("shoulder_to_elbow")[0] == pytest.approx(1.0, abs=0.001)


def test_arm_pick_on_an_agent_without_joints_fails(sim):
    robot = Agent.from_mesh(CUBE, CUBE, Pose([0, 0, 0.1]), sim_core=sim, controller="omni")
    box = cube(sim, [1, 0, 0.05])
    pick = PickAction(target_object_id=box.body_id, joint_targets=[0.1])
    robot.add_action(pick)
    run_until(sim, pick)
    assert pick.status is ActionStatus.FAILED and "need an agent with joints" in pick.error_message


# ----- manager -----------------------------------------------------------------------------


def test_manager_sets_joint_targets_for_arms_only(sim):
    mgr = AgentManager(sim_core=sim)
    arms = [arm(sim, user_data={"index": i}) for i in range(3)]
    rover = Agent.from_mesh(CUBE, CUBE, Pose([5, 0, 0.1]), sim_core=sim)
    for agent in [*arms, rover]:
        mgr.add_object(agent)
    called = []

    def factory(agent):
        called.append(agent)
        return [agent.user_data["index"] * 0.3, 0.0, 0.0, 0.0]

    mgr.set_joints_targets_all(factory, max_force=1000.0)
    assert called == arms
    for _ in range(10):
        sim.step_once()
    assert [x.get_joint_state(0)[0] for x in arms] == pytest.approx([0.0, 0.3, 0.6])
    assert arms[1].joints.forces[0] == 1000.0


# ----- physics -----------------------------------------------------------------------------


def test_physics_arm_is_driven_by_motors():
    sim = MultiRobotSimulationCore(headless_params(physics=True, timestep=1 / 240))
    try:
        a = Agent.from_urdf("kuka_iiwa", use_fixed_base=True, sim_core=sim)
        assert a.joints.kinematic is False
        a.set_joint_target(1, 0.5, max_force=300.0)
        for _ in range(480):
            sim.step_once()
        assert a.is_joint_at_target(1, 0.5, tolerance=0.02)
        assert a.get_joint_state(1)[0] == pytest.approx(
            p.getJointState(a.body_id, 1, physicsClientId=sim.client)[0]
        )
    finally:
        sim.close()


def test_physics_joint_action_completes_even_with_a_tight_tolerance():
    sim = MultiRobotSimulationCore(headless_params(physics=True, timestep=1 / 240))
    try:
        a = Agent.from_urdf("kuka_iiwa", use_fixed_base=True, sim_core=sim)
        action = JointAction(target_joint_positions={"lbr_iiwa_joint_2": 0.4}, tolerance=0.002)
        a.add_action(action)
        run_until(sim, action, limit=2000)
        assert action.status is ActionStatus.COMPLETED
        assert abs(a.get_joint_state(1)[0] - 0.4) <= 0.002
    finally:
        sim.close()
