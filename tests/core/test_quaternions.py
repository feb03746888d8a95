"""Quaternion helpers, checked against closed forms, each other and PyBullet's math functions.

PyBullet's Euler and matrix helpers work in double precision; ``multiplyTransforms`` and
``getQuaternionFromAxisAngle`` round to float32, hence their looser tolerance.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from fleet_async.core.geometry.quaternions import (
    SlerpPrecomp,
    compose_poses_batch,
    euler_from_quat,
    quat_angle_between,
    quat_from_euler,
    quat_from_rotvec,
    quat_multiply,
    quat_multiply_batch,
    quat_slerp,
    quat_slerp_batch,
    quat_slerp_precompute,
    quat_to_rot_matrix,
    rotate_vector,
    rotate_vectors_batch,
    yaw_from_quats,
)

FLOAT32_TOL = 2e-6
S = math.sqrt(0.5)
QZ90 = (0.0, 0.0, S, S)  # 90 degrees about +Z


def random_quats(n: int, seed: int = 0) -> np.ndarray:
    q = np.random.default_rng(seed).normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def random_vecs(n: int, seed: int = 1) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-5.0, 5.0, size=(n, 3))


def assert_same_rotation(actual, expected, atol: float) -> None:
    """Equal up to the sign of the quaternion (PyBullet returns either of q and -q)."""
    actual, expected = np.asarray(actual), np.asarray(expected)
    sign = 1.0 if float(actual @ expected) >= 0 else -1.0
    np.testing.assert_allclose(actual, sign * expected, rtol=0, atol=atol)


# --- rotation matrix and vectors ------------------------------------------------------


def test_rot_matrix_of_identity_and_quarter_turn():
    assert quat_to_rot_matrix((0, 0, 0, 1)) == (1, 0, 0, 0, 1, 0, 0, 0, 1)
    expected = (0, -1, 0, 1, 0, 0, 0, 0, 1)
    np.testing.assert_allclose(quat_to_rot_matrix(QZ90), expected, rtol=0, atol=1e-15)


def test_rot_matrix_matches_pybullet_and_ignores_scale():
    for q in random_quats(50):
        ours = quat_to_rot_matrix(q)
        np.testing.assert_allclose(ours, p.getMatrixFromQuaternion(q.tolist()), atol=1e-12)
        np.testing.assert_allclose(quat_to_rot_matrix(3.5 * q), ours, atol=1e-12)
    assert len(ours) == 9 and all(type(v) is float for v in ours)


def test_rot_matrix_rejects_zero_and_wrong_length():
    with pytest.raises(ValueError, match="zero-norm"):
        quat_to_rot_matrix((0, 0, 0, 0))
    with pytest.raises(ValueError, match=r"quat: expected 4 numbers, got \[0, 0, 1\]"):
        quat_to_rot_matrix([0, 0, 1])


def test_rotate_vector_quarter_turn_and_matrix_agreement():
    np.testing.assert_allclose(rotate_vector([1, 0, 0], QZ90), [0, 1, 0], atol=1e-15)
    for q, v in zip(random_quats(50), random_vecs(50), strict=True):
        matrix = np.array(p.getMatrixFromQuaternion(q.tolist())).reshape(3, 3)
        np.testing.assert_allclose(rotate_vector(v, q), matrix @ v, atol=1e-12)
        np.testing.assert_allclose(rotate_vector(v, -2.0 * q), matrix @ v, atol=1e-12)


def test_rotate_vector_rejects_wrong_length():
    with pytest.raises(ValueError, match="vec: expected 3 numbers"):
        rotate_vector([1, 0], QZ90)


# --- construction from rotation vectors and Euler angles ------------------------------


def test_quat_from_rotvec_closed_forms():
    assert quat_from_rotvec([0, 0, 0]).tolist() == [0.0, 0.0, 0.0, 1.0]
    np.testing.assert_allclose(quat_from_rotvec([math.pi / 2, 0, 0]), [S, 0, 0, S], atol=1e-15)
    tiny = quat_from_rotvec([2e-9, 0, -4e-9])
    np.testing.assert_allclose(tiny, [1e-9, 0, -2e-9, 1.0], rtol=1e-15, atol=0)


def test_quat_from_rotvec_matches_pybullet_axis_angle():
    for v in random_vecs(30):
        angle = float(np.linalg.norm(v))
        expected = p.getQuaternionFromAxisAngle((v / angle).tolist(), angle)
        np.testing.assert_allclose(quat_from_rotvec(v), expected, atol=FLOAT32_TOL)
    with pytest.raises(ValueError, match="rotvec"):
        quat_from_rotvec([1, 2])


def test_euler_conversions_match_pybullet():
    rng = np.random.default_rng(0)
    for rpy in rng.uniform([-3, -1.5, -3], [3, 1.5, 3], size=(50, 3)):
        q = quat_from_euler(*rpy)
        np.testing.assert_allclose(q, p.getQuaternionFromEuler(rpy.tolist()), atol=1e-15)
        np.testing.assert_allclose(euler_from_quat(q), rpy, atol=1e-12)
        np.testing.assert_allclose(euler_from_quat(q), p.getEulerFromQuaternion(q), atol=1e-12)


@pytest.mark.parametrize("pitch", [math.pi / 2, -math.pi / 2])
def test_euler_at_gimbal_lock_puts_everything_in_yaw(pitch):
    q = quat_from_euler(0.4, pitch, 0.3)
    roll, got_pitch, yaw = euler_from_quat(q)
    assert roll == 0.0
    assert got_pitch == pitch
    assert quat_angle_between(quat_from_euler(roll, got_pitch, yaw), q) < 1e-9
    np.testing.assert_allclose((roll, got_pitch, yaw), p.getEulerFromQuaternion(q), atol=1e-9)


# --- products and angles --------------------------------------------------------------


def test_quat_multiply_applies_right_operand_first():
    v = np.array([0.3, -1.2, 2.0])
    for q1, q2 in zip(random_quats(30, seed=2), random_quats(30, seed=3), strict=True):
        product = quat_multiply(q1, q2)
        both = rotate_vector(rotate_vector(v, q2), q1)
        np.testing.assert_allclose(rotate_vector(v, product), both, atol=1e-12)
        expected = p.multiplyTransforms([0, 0, 0], q1.tolist(), [0, 0, 0], q2.tolist())[1]
        assert_same_rotation(product, expected, FLOAT32_TOL)
    rx90, ry90 = (S, 0, 0, S), (0, S, 0, S)
    np.testing.assert_allclose(quat_multiply(rx90, ry90), [0.5, 0.5, 0.5, 0.5], atol=1e-15)
    np.testing.assert_allclose(quat_multiply(ry90, rx90), [0.5, 0.5, -0.5, 0.5], atol=1e-15)


def test_quat_multiply_rejects_wrong_length():
    with pytest.raises(ValueError, match="q2: expected 4 numbers"):
        quat_multiply(QZ90, [0, 0, 1])


def test_angle_between_closed_forms_and_double_cover():
    identity = (0, 0, 0, 1)
    assert quat_angle_between(identity, QZ90) == pytest.approx(math.pi / 2, abs=1e-15)
    assert quat_angle_between(QZ90, [-c for c in QZ90]) == 0.0
    assert quat_angle_between(identity, (0, 0, 5, 5)) == pytest.approx(math.pi / 2, abs=1e-15)
    three_quarters = quat_from_rotvec([0, 0, 1.5 * math.pi])
    assert quat_angle_between(identity, three_quarters) == pytest.approx(math.pi / 2, abs=1e-12)
    # atan2 keeps tiny angles exact where acos(dot) would return 0 or ~1e-8.
    assert quat_angle_between(identity, quat_from_rotvec([0, 1e-10, 0])) == pytest.approx(
        1e-10, rel=1e-9
    )


def test_angle_between_matches_relative_rotation_magnitude():
    for q0, q1 in zip(random_quats(30, seed=4), random_quats(30, seed=5), strict=True):
        *_, w = quat_multiply(q1, q0 * [-1, -1, -1, 1])
        expected = 2 * math.acos(min(1.0, abs(w)))
        assert quat_angle_between(q0, q1) == pytest.approx(expected, abs=1e-7)


def test_angle_between_rejects_zero_quaternion():
    with pytest.raises(ValueError, match="q1: zero-norm"):
        quat_angle_between(QZ90, (0, 0, 0, 0))


# --- slerp ----------------------------------------------------------------------------


def test_slerp_precompute_values_and_flip():
    pre = quat_slerp_precompute((0, 0, 0, 1), QZ90)
    assert isinstance(pre, SlerpPrecomp)
    assert pre.dot == pytest.approx(S, abs=1e-15)
    assert pre.theta_0 == pytest.approx(math.pi / 4, abs=1e-15)
    assert pre.sin_theta_0 == pytest.approx(S, abs=1e-15)
    assert pre.needs_flip is False
    flipped = quat_slerp_precompute((0, 0, 0, 1), [-c for c in QZ90])
    assert flipped.needs_flip is True
    assert flipped.dot == pre.dot and flipped.theta_0 == pre.theta_0


def test_slerp_endpoints_midpoint_and_shortest_path():
    q0, q1 = (0.0, 0.0, 0.0, 1.0), QZ90
    pre = quat_slerp_precompute(q0, q1)
    np.testing.assert_allclose(quat_slerp(q0, q1, 0.0, pre), q0, atol=1e-15)
    np.testing.assert_allclose(quat_slerp(q0, q1, 1.0, pre), q1, atol=1e-15)
    half = [0, 0, math.sin(math.pi / 8), math.cos(math.pi / 8)]
    np.testing.assert_allclose(quat_slerp(q0, q1, 0.5, pre), half, atol=1e-15)
    neg = [-c for c in q1]
    np.testing.assert_allclose(
        quat_slerp(q0, neg, 0.5, quat_slerp_precompute(q0, neg)), half, atol=1e-15
    )


def test_slerp_moves_at_constant_angular_rate():
    for q0, q1 in zip(random_quats(20, seed=6), random_quats(20, seed=7), strict=True):
        pre = quat_slerp_precompute(q0, q1)
        total = quat_angle_between(q0, q1)
        for t in (0.1, 0.35, 0.8):
            q = quat_slerp(q0, q1, t, pre)
            assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-12)
            assert quat_angle_between(q0, q) == pytest.approx(t * total, abs=1e-9)


def test_slerp_near_identical_falls_back_to_normalised_lerp():
    q0 = np.array([0.0, 0.0, 0.0, 1.0])
    q1 = quat_from_rotvec([0, 0, 2e-9])
    pre = quat_slerp_precompute(q0, q1)
    assert pre.sin_theta_0 < 1e-6
    q = quat_slerp(q0, q1, 0.5, pre)
    assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_allclose(q, quat_from_rotvec([0, 0, 1e-9]), atol=1e-15)


def test_slerp_batch_matches_scalar_and_handles_identical_rows():
    q0, q1 = random_quats(40, seed=8), random_quats(40, seed=9)
    q1[5] = q0[5]  # sin_theta0 == 0: must not divide by zero
    raw_dot = np.einsum("ij,ij->i", q0, q1)
    q1c = np.where(raw_dot[:, None] < 0, -q1, q1)
    dot = np.minimum(np.abs(raw_dot), 1.0)
    theta0 = np.arccos(dot)
    t = np.random.default_rng(10).uniform(0, 1, size=40)
    with np.errstate(all="raise"):
        batch = quat_slerp_batch(q0, q1c, t, dot, theta0, np.sin(theta0))
    for i in range(40):
        scalar = quat_slerp(q0[i], q1[i], float(t[i]), quat_slerp_precompute(q0[i], q1[i]))
        np.testing.assert_allclose(batch[i], scalar, atol=1e-12)
    np.testing.assert_allclose(batch[5], q0[5], atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(batch, axis=1), 1.0, atol=1e-12)


# --- batched helpers ------------------------------------------------------------------


def test_quat_multiply_batch_matches_scalar():
    q1, q2 = random_quats(64, seed=11), random_quats(64, seed=12)
    batch = quat_multiply_batch(q1, q2)
    assert batch.shape == (64, 4)
    for i in range(64):
        np.testing.assert_allclose(batch[i], quat_multiply(q1[i], q2[i]), rtol=0, atol=1e-15)


def test_quat_multiply_batch_rejects_bad_shapes():
    with pytest.raises(ValueError, match=r"q1: expected an \(N, 4\) array, got shape \(2, 3\)"):
        quat_multiply_batch(np.zeros((2, 3)), np.zeros((2, 4)))
    with pytest.raises(ValueError, match="row counts differ"):
        quat_multiply_batch(random_quats(2), random_quats(3))


def test_rotate_vectors_batch_matches_scalar_and_accepts_non_unit():
    v, q = random_vecs(64), random_quats(64, seed=13)
    batch = rotate_vectors_batch(v, q)
    scaled = rotate_vectors_batch(v, q * np.linspace(0.1, 7.0, 64)[:, None])
    for i in range(64):
        np.testing.assert_allclose(batch[i], rotate_vector(v[i], q[i]), atol=1e-12)
    np.testing.assert_allclose(scaled, batch, atol=1e-12)


def test_rotate_vectors_batch_rejects_zero_quaternion_and_mismatch():
    q = random_quats(4)
    q[2] = 0.0
    with pytest.raises(ValueError, match=r"quats\[2\]: zero-norm"):
        rotate_vectors_batch(random_vecs(4), q)
    with pytest.raises(ValueError, match="row counts differ"):
        rotate_vectors_batch(random_vecs(3), random_quats(4))


def test_compose_poses_batch_matches_pybullet_multiply_transforms():
    n = 32
    parent_pos, rel_pos = random_vecs(n, seed=14), random_vecs(n, seed=15)
    parent_q, rel_q = random_quats(n, seed=16), random_quats(n, seed=17)
    pos, quat = compose_poses_batch(parent_pos, parent_q, rel_pos, rel_q)
    assert pos.shape == (n, 3) and quat.shape == (n, 4)
    for i in range(n):
        exp_pos, exp_q = p.multiplyTransforms(
            parent_pos[i].tolist(), parent_q[i].tolist(), rel_pos[i].tolist(), rel_q[i].tolist()
        )
        np.testing.assert_allclose(pos[i], exp_pos, atol=1e-5)  # float32 on |pos| <~ 15 m
        assert_same_rotation(quat[i], exp_q, FLOAT32_TOL)
        np.testing.assert_allclose(quat[i], quat_multiply(parent_q[i], rel_q[i]), atol=1e-15)
        exact = parent_pos[i] + rotate_vector(rel_pos[i], parent_q[i])
        np.testing.assert_allclose(pos[i], exact, atol=1e-12)


def test_compose_poses_batch_rejects_mismatched_rows():
    with pytest.raises(ValueError, match="parent_pos and rel_pos"):
        compose_poses_batch(random_vecs(2), random_quats(3), random_vecs(3), random_quats(3))


def test_yaw_from_quats_matches_pybullet_and_scalar():
    q = random_quats(100, seed=18)
    yaw = yaw_from_quats(q)
    assert yaw.shape == (100,)
    for i in range(100):
        assert yaw[i] == pytest.approx(p.getEulerFromQuaternion(q[i].tolist())[2], abs=1e-9)
        assert yaw[i] == pytest.approx(euler_from_quat(q[i])[2], abs=1e-12)
    np.testing.assert_allclose(yaw_from_quats(4.0 * q), yaw, atol=1e-12)
    np.testing.assert_allclose(yaw_from_quats([QZ90]), [math.pi / 2], atol=1e-15)
    with pytest.raises(ValueError, match="quats"):
        yaw_from_quats(np.zeros((3, 3)))
