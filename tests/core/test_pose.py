"""Pose: validation, normalisation, conversions and frame algebra."""

from __future__ import annotations

import itertools
import math
import re

import numpy as np
import pybullet as p
import pytest

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.quaternions import quat_angle_between

FLOAT32_TOL = 2e-6
S = math.sqrt(0.5)


def random_poses(n: int, seed: int = 0) -> list[Pose]:
    rng = np.random.default_rng(seed)
    return [Pose(rng.uniform(-5, 5, 3), rng.normal(size=4)) for _ in range(n)]


def test_defaults_dtype_and_copying():
    source = np.array([1, 2, 3])
    pose = Pose(source)
    source[0] = 99
    assert pose.position.dtype == np.float64 and pose.position.shape == (3,)
    assert pose.position.tolist() == [1.0, 2.0, 3.0]
    assert pose.orientation.dtype == np.float64
    assert pose.orientation.tolist() == [0.0, 0.0, 0.0, 1.0]
    other = Pose([0, 0, 0])
    other.orientation[0] = 5.0  # each pose owns its identity array
    assert Pose([0, 0, 0]).orientation.tolist() == [0.0, 0.0, 0.0, 1.0]


def test_non_unit_quaternion_is_normalised():
    pose = Pose([0, 0, 0], [0, 0, 2, 2])
    np.testing.assert_allclose(pose.orientation, [0, 0, S, S], rtol=0, atol=1e-15)
    assert math.hypot(*pose.orientation) == pytest.approx(1.0, abs=1e-15)
    tiny = Pose([0, 0, 0], [0, 0, 1e-300, 1e-300])
    huge = Pose([0, 0, 0], [0, 0, 1e300, 1e300])
    np.testing.assert_allclose(tiny.orientation, [0, 0, S, S], atol=1e-15)
    np.testing.assert_allclose(huge.orientation, [0, 0, S, S], atol=1e-15)


def test_unit_quaternion_is_stored_unchanged():
    q = [0.1, -0.2, 0.3, math.sqrt(1 - 0.14)]
    assert Pose([0, 0, 0], q).orientation.tolist() == q


@pytest.mark.parametrize(
    "bad",
    [[1, 2], [1, 2, 3, 4], [1, 2, math.nan], [1, math.inf, 3], "abc", ["1", "2", "3"], None,
     [[1, 2, 3]], 5.0, {"x": 1}],
)  # fmt: skip
def test_bad_position_raises_naming_field_and_value(bad):
    expected = f"Pose.position: expected 3 finite numbers [x, y, z], got {bad!r}"
    with pytest.raises(ValueError, match=f"^{re.escape(expected)}$"):
        Pose(bad)


@pytest.mark.parametrize("bad", [[0, 0, 1], [0, 0, 0, 1, 0], [math.nan, 0, 0, 1], "wxyz"])
def test_bad_orientation_raises_naming_field(bad):
    with pytest.raises(ValueError, match=r"^Pose\.orientation: expected 4 finite numbers"):
        Pose([0, 0, 0], bad)


def test_zero_quaternion_raises():
    with pytest.raises(ValueError, match=r"^Pose\.orientation: zero-norm quaternion"):
        Pose([0, 0, 0], [0, 0, 0, 0])


def test_equality_is_exact_and_poses_are_unhashable():
    a = Pose([1, 2, 3], [0, 0, 1, 1])
    assert a == Pose([1.0, 2.0, 3.0], [0, 0, 1, 1])
    assert a != Pose([1, 2, 3 + 1e-12], [0, 0, 1, 1])
    assert a != Pose([1, 2, 3], [0, 0, 1, 1.0000001])
    assert a != (a.position, a.orientation)
    with pytest.raises(TypeError):
        hash(a)


def test_repr_round_trips_values():
    pose = Pose([1, 2.5, -3], [0, 0, 0, 1])
    assert repr(pose) == "Pose(position=[1.0, 2.5, -3.0], orientation=[0.0, 0.0, 0.0, 1.0])"


def test_copy_is_equal_and_independent():
    pose = Pose([1, 2, 3], [0, 0, 1, 1])
    clone = pose.copy()
    assert clone == pose
    clone.position[0] = 7.0
    clone.orientation[3] = 0.0
    assert pose.position[0] == 1.0 and pose.orientation[3] == pytest.approx(S)


def test_from_arrays_unchecked_wraps_without_copy():
    pos, quat = np.array([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 0.0, 1.0])
    pose = Pose.from_arrays_unchecked(pos, quat)
    assert pose.position is pos and pose.orientation is quat


def test_coordinate_properties_are_floats():
    pose = Pose.from_xyz(1, 2, 3)
    assert (pose.x, pose.y, pose.z) == (1.0, 2.0, 3.0)
    assert all(type(v) is float for v in (pose.x, pose.y, pose.z))
    assert pose.orientation.tolist() == [0.0, 0.0, 0.0, 1.0]


def test_from_euler_matches_pybullet_and_properties_read_back():
    pose = Pose.from_euler(1, 2, 3, roll=0.1, pitch=-0.2, yaw=2.5)
    assert pose.position.tolist() == [1.0, 2.0, 3.0]
    expected = p.getQuaternionFromEuler([0.1, -0.2, 2.5])
    np.testing.assert_allclose(pose.orientation, expected, rtol=0, atol=1e-15)
    assert pose.roll == pytest.approx(0.1, abs=1e-12)
    assert pose.pitch == pytest.approx(-0.2, abs=1e-12)
    assert pose.yaw == pytest.approx(2.5, abs=1e-12)
    np.testing.assert_allclose(pose.as_euler(), p.getEulerFromQuaternion(expected), atol=1e-12)
    with pytest.raises(ValueError, match=r"^Pose\.from_euler: expected 3 finite numbers"):
        Pose.from_euler(0, 0, 0, yaw=math.nan)


def test_pybullet_round_trip_uses_python_floats():
    pos, orn = (1.5, -2.0, 0.25), p.getQuaternionFromEuler([0.3, 0.2, 0.1])
    pose = Pose.from_pybullet(pos, orn)
    out_pos, out_orn = pose.as_position_orientation()
    assert out_pos == [1.5, -2.0, 0.25]
    np.testing.assert_allclose(out_orn, orn, rtol=0, atol=1e-15)
    assert all(type(v) is float for v in out_pos + out_orn)
    assert isinstance(out_pos, list) and isinstance(out_orn, list)
    assert pose.as_tuple() == (out_pos, out_orn)
    assert Pose.from_pybullet(out_pos, out_orn) == pose


def test_compose_matches_pybullet_multiply_transforms():
    poses = random_poses(20)
    for a, b in itertools.pairwise(poses):
        exp_pos, exp_orn = p.multiplyTransforms(*a.as_tuple(), *b.as_tuple())
        c = a.compose(b)
        np.testing.assert_allclose(c.position, exp_pos, atol=1e-5)  # PyBullet rounds to float32
        assert quat_angle_between(c.orientation, exp_orn) < 1e-3
        np.testing.assert_allclose(np.linalg.norm(c.orientation), 1.0, atol=1e-15)


def test_compose_with_known_values():
    parent = Pose([1, 0, 0], [0, 0, S, S])  # at x=1, facing +Y
    child = parent.compose(Pose([2, 0, 0.5], [0, 0, S, S]))
    np.testing.assert_allclose(child.position, [1, 2, 0.5], atol=1e-15)
    np.testing.assert_allclose(child.orientation, [0, 0, 1, 0], atol=1e-15)


def test_inverse_undoes_compose():
    identity = Pose([0, 0, 0])
    for pose in random_poses(20, seed=1):
        for result in (pose.compose(pose.inverse()), pose.inverse().compose(pose)):
            np.testing.assert_allclose(result.position, identity.position, atol=1e-12)
            assert quat_angle_between(result.orientation, identity.orientation) < 1e-7
    inv = Pose([1, 0, 0], [0, 0, S, S]).inverse()
    np.testing.assert_allclose(inv.position, [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(inv.orientation, [0, 0, -S, S], atol=1e-15)


def test_distance_to_ignores_orientation():
    a = Pose([0, 0, 0])
    b = Pose([3, 4, 0], [0, 0, 1, 0])
    assert a.distance_to(b) == 5.0
    assert b.distance_to(a) == 5.0
    assert a.distance_to(a) == 0.0
