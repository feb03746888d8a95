"""Kinematic-limit helpers, and the geometry API (fleet_async.geometry) naming the owners."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fleet_async import geometry
from fleet_async.core.geometry import limits, pose, quaternions, waypoints
from fleet_async.core.geometry.limits import (
    as_axes,
    clamp_vec_to_limit,
    is_scalar,
    projected_axis_limit,
)

S2 = math.sqrt(0.5)


@pytest.mark.parametrize("value", [1, 1.5, -2, np.float64(2.0), np.int32(3), np.array(2.0)])
def test_is_scalar_accepts_numbers_and_0d_arrays(value):
    assert is_scalar(value) is True


@pytest.mark.parametrize("value", [[1.0], (1, 2, 3), np.array([1.0]), np.zeros(3), "1", None])
def test_is_scalar_rejects_sequences_and_non_numbers(value):
    assert is_scalar(value) is False


def test_as_axes_broadcasts_scalars_and_copies_sequences():
    assert as_axes(2).tolist() == [2.0, 2.0, 2.0]
    assert as_axes(np.array(0.5), dim=2).tolist() == [0.5, 0.5]
    source = np.array([1.0, 2.0, 3.0])
    axes = as_axes(source)
    axes[0] = 9.0
    assert source[0] == 1.0
    assert as_axes((1, 2), dim=2).dtype == np.float64


def test_as_axes_rejects_wrong_shape_naming_the_value():
    with pytest.raises(ValueError, match=r"expected a scalar or 3 per-axis values, got \[1, 2\]"):
        as_axes([1, 2])
    with pytest.raises(ValueError, match="per-axis"):
        as_axes(np.zeros((3, 1)))


def test_projected_axis_limit_is_the_tightest_axis():
    caps = [1.0, 2.0, math.inf]
    assert projected_axis_limit(caps, [1.0, 0.0, 0.0]) == 1.0
    assert projected_axis_limit(caps, [0.0, -1.0, 0.0]) == 2.0
    # 0.6 / 1.0 beats 0.8 / 2.0, so x binds: v = 1 / 0.6.
    assert projected_axis_limit(caps, [0.6, 0.8, 0.0]) == pytest.approx(1 / 0.6, rel=1e-15)
    assert projected_axis_limit(caps, np.array([0.0, 0.0, 1.0])) == math.inf
    assert projected_axis_limit(caps, [0.0, 0.0, 0.0]) == math.inf


def test_projected_axis_limit_zero_caps_and_scalars():
    assert projected_axis_limit([1.0, 0.0, 1.0], [S2, S2, 0.0]) == 0.0
    assert projected_axis_limit([1.0, 0.0, 1.0], [S2, 0.0, S2]) == pytest.approx(1 / S2)
    assert projected_axis_limit(2.5, [S2, S2, 0.0]) == 2.5  # scalar = Euclidean bound
    assert projected_axis_limit([1.0, 2.0], [0.0, 1.0]) == 2.0


def test_projected_axis_limit_rejects_mismatched_direction():
    with pytest.raises(ValueError, match=r"direction_unit: expected 3 components, got \[1, 0\]"):
        projected_axis_limit([1.0, 1.0, 1.0], [1, 0])


def test_clamp_scalar_is_a_magnitude_clamp():
    np.testing.assert_allclose(
        clamp_vec_to_limit([3.0, 4.0, 0.0], 1.0), [0.6, 0.8, 0.0], atol=1e-15
    )
    assert clamp_vec_to_limit([0.3, 0.4, 0.0], 1.0).tolist() == [0.3, 0.4, 0.0]
    assert clamp_vec_to_limit([3.0, 4.0], 0).tolist() == [0.0, 0.0]
    assert np.linalg.norm(clamp_vec_to_limit([1e3, -2e3, 5e2], 2.0)) == pytest.approx(2.0)


@pytest.mark.parametrize("limit", [math.inf, np.inf, math.nan])
def test_clamp_non_finite_scalar_returns_vec_unchanged(limit):
    vec = np.array([1e9, -1e9, 3.0])
    assert clamp_vec_to_limit(vec, limit) is vec


def test_clamp_rejects_negative_scalar():
    with pytest.raises(ValueError, match=r"limit: expected a non-negative scalar cap, got -1\.0"):
        clamp_vec_to_limit([1.0, 0.0, 0.0], -1.0)


def test_clamp_per_axis_clips_each_component():
    out = clamp_vec_to_limit([3.0, -4.0, 0.5], [1.0, 2.0, 1.0])
    assert out.tolist() == [1.0, -2.0, 0.5]
    assert clamp_vec_to_limit([3.0, -4.0, 0.5], (math.inf, 1.0, 0.0)).tolist() == [3.0, -1.0, 0.0]
    with pytest.raises(ValueError, match="per-axis"):
        clamp_vec_to_limit([1.0, 2.0, 3.0], [1.0, 1.0])


def test_public_names_resolve_to_the_owning_modules():
    assert geometry.Pose is pose.Pose
    assert geometry.Path is waypoints.Path
    for name in geometry.__all__:
        owners = [m for m in (pose, waypoints, quaternions, limits) if name in m.__all__]
        assert [getattr(m, name) for m in owners] == [getattr(geometry, name)], name
