"""Velocity frames, vector parameters, link/joint lookup, offset poses, grids, nearest search."""

from __future__ import annotations

import logging
import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pybullet as p
import pybullet_data
import pytest

from fleet_async.core.geometry.approach import calculate_offset_pose, find_nearest
from fleet_async.core.geometry.grids import (
    grid_execution,
    grid_to_world,
    grid_to_world_2d,
    world_to_grid,
    world_to_grid_2d,
)
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.vectors import (
    body_to_world_velocity_2d,
    body_to_world_velocity_3d,
    normalize_vector_param,
)
from fleet_async.core.world.links import (
    joint_index,
    link_index,
    resolve_joint_index,
    resolve_link_index,
)

# ----- velocities ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("vx", "vy", "yaw", "expected"),
    [
        (1.0, 0.0, 0.0, (1.0, 0.0)),
        (1.0, 0.0, math.pi / 2, (0.0, 1.0)),
        (0.0, 1.0, math.pi / 2, (-1.0, 0.0)),
        (2.0, -1.0, math.pi, (-2.0, 1.0)),
        (1.0, 1.0, -math.pi / 4, (math.sqrt(2), 0.0)),
    ],
)
def test_body_to_world_velocity_2d(
    vx: float, vy: float, yaw: float, expected: tuple[float, float]
) -> None:
    assert body_to_world_velocity_2d(vx, vy, yaw) == pytest.approx(expected, abs=1e-12)


def test_body_to_world_velocity_3d_matches_pybullet_rotation() -> None:
    q = p.getQuaternionFromEuler([0.3, -0.7, 1.2])
    matrix = np.array(p.getMatrixFromQuaternion(q)).reshape(3, 3)

    result = body_to_world_velocity_3d(0.5, -1.0, 2.0, q)

    assert isinstance(result, tuple)
    assert len(result) == 3
    assert result == pytest.approx(tuple(matrix @ [0.5, -1.0, 2.0]), abs=1e-12)


def test_body_to_world_velocity_3d_yaw_90_and_unnormalised_quaternion() -> None:
    s = math.sin(math.pi / 4)
    assert body_to_world_velocity_3d(1.0, 0.0, 0.0, (0.0, 0.0, s, s)) == pytest.approx(
        (0.0, 1.0, 0.0), abs=1e-12
    )
    assert body_to_world_velocity_3d(1.0, 0.0, 0.0, (0.0, 0.0, 3.0, 3.0)) == pytest.approx(
        (0.0, 1.0, 0.0), abs=1e-12
    )


def test_body_to_world_velocity_3d_zero_quaternion_raises() -> None:
    with pytest.raises(ValueError, match="zero"):
        body_to_world_velocity_3d(1.0, 0.0, 0.0, (0.0, 0.0, 0.0, 0.0))


# ----- normalize_vector_param ------------------------------------------------------------


def test_normalize_vector_param_scalar_and_list() -> None:
    np.testing.assert_array_equal(normalize_vector_param(2.0, "max_vel"), [2.0, 2.0, 2.0])
    np.testing.assert_array_equal(normalize_vector_param(3, "max_vel", 2), [3.0, 3.0])
    np.testing.assert_array_equal(normalize_vector_param([1, 2, 3], "max_vel"), [1.0, 2.0, 3.0])
    out = normalize_vector_param(np.float32(1.5), "a", 4)
    assert out.dtype == np.float64
    assert out.shape == (4,)


def test_normalize_vector_param_returns_a_copy() -> None:
    source = np.array([1.0, 2.0, 3.0])

    out = normalize_vector_param(source, "v")
    out[0] = 99.0

    assert source[0] == 1.0


@pytest.mark.parametrize(
    "bad",
    [[1.0, 2.0], [1.0, 2.0, 3.0, 4.0], [[1.0, 2.0, 3.0]], "abc", True, [1.0, "2", 3.0], None],
)
def test_normalize_vector_param_bad_shape_or_type_names_param(bad: object) -> None:
    with pytest.raises(ValueError, match="max_accel"):
        normalize_vector_param(bad, "max_accel")  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", [math.nan, math.inf, [1.0, math.nan, 0.0], [0.0, -math.inf, 1]])
def test_normalize_vector_param_rejects_non_finite(bad: object) -> None:
    with pytest.raises(ValueError, match="max_vel: expected finite"):
        normalize_vector_param(bad, "max_vel")  # type: ignore[arg-type]


# ----- link / joint lookup ----------------------------------------------------------------


@pytest.fixture
def client() -> Iterator[int]:
    cid = p.connect(p.DIRECT)
    p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=cid)
    yield cid
    p.disconnect(cid)


def test_resolve_link_index_by_name_and_base(client: int) -> None:
    r2d2 = p.loadURDF("r2d2.urdf", physicsClientId=client)

    assert resolve_link_index(r2d2, "base_link", physics_client_id=client) == -1
    assert resolve_link_index(r2d2, "right_leg", physics_client_id=client) == 0
    assert resolve_link_index(r2d2, "head", physics_client_id=client) == 13
    assert resolve_link_index(r2d2, "box", physics_client_id=client) == 14


def test_resolve_link_index_base_by_own_name_and_base_link_alias(client: int) -> None:
    kuka = p.loadURDF("kuka_iiwa/model.urdf", physicsClientId=client)

    assert resolve_link_index(kuka, "lbr_iiwa_link_0", physics_client_id=client) == -1
    assert resolve_link_index(kuka, "base_link", physics_client_id=client) == -1
    assert resolve_link_index(kuka, "lbr_iiwa_link_7", physics_client_id=client) == 6


def test_resolve_link_index_int_passthrough_and_range(client: int) -> None:
    kuka = p.loadURDF("kuka_iiwa/model.urdf", physicsClientId=client)

    assert resolve_link_index(kuka, -1, physics_client_id=client) == -1
    assert resolve_link_index(kuka, 6, physics_client_id=client) == 6
    assert resolve_link_index(kuka, np.int64(3), physics_client_id=client) == 3
    with pytest.raises(ValueError, match=r"out of range \[-1, 7\)"):
        resolve_link_index(kuka, 7, physics_client_id=client)
    with pytest.raises(ValueError, match="out of range"):
        resolve_link_index(kuka, -2, physics_client_id=client)


def test_resolve_link_index_unknown_name_lists_known_links(client: int) -> None:
    kuka = p.loadURDF("kuka_iiwa/model.urdf", physicsClientId=client)

    with pytest.raises(ValueError, match="no link named 'gripper'") as info:
        link_index(kuka, "gripper", physics_client_id=client)

    assert "lbr_iiwa_link_0" in str(info.value)
    assert "lbr_iiwa_link_7" in str(info.value)


def test_resolve_index_returns_minus_one_for_an_unknown_name(client: int, caplog) -> None:
    # Seed, tools.resolve_link_index: "Returns -1 if link is "base_link" or if link name not
    # found"; resolve_joint_index: "Returns -1 if joint name not found". Logged, with the names.
    kuka = p.loadURDF("kuka_iiwa/model.urdf", physicsClientId=client)
    with caplog.at_level(logging.WARNING):
        assert resolve_link_index(kuka, "gripper", physics_client_id=client) == -1
        assert resolve_joint_index(kuka, "elbow", physics_client_id=client) == -1
    assert "no link named 'gripper'" in caplog.text and "lbr_iiwa_link_7" in caplog.text
    assert "no joint named 'elbow'" in caplog.text


def test_resolve_link_index_rejects_bad_types_and_bodies(client: int) -> None:
    kuka = p.loadURDF("kuka_iiwa/model.urdf", physicsClientId=client)

    with pytest.raises(TypeError, match="link"):
        resolve_link_index(kuka, 1.0, physics_client_id=client)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="link"):
        resolve_link_index(kuka, True, physics_client_id=client)
    with pytest.raises(ValueError, match="No body with id 999"):
        resolve_link_index(999, "base_link", physics_client_id=client)


def test_resolve_joint_index_by_name_and_int(client: int) -> None:
    r2d2 = p.loadURDF("r2d2.urdf", physicsClientId=client)

    assert resolve_joint_index(r2d2, "base_to_right_leg", physics_client_id=client) == 0
    assert resolve_joint_index(r2d2, "head_swivel", physics_client_id=client) == 13
    assert resolve_joint_index(r2d2, 14, physics_client_id=client) == 14
    with pytest.raises(ValueError, match=r"out of range \[0, 15\)"):
        resolve_joint_index(r2d2, 15, physics_client_id=client)
    with pytest.raises(ValueError, match="out of range"):
        resolve_joint_index(r2d2, -1, physics_client_id=client)


def test_resolve_joint_index_unknown_name_lists_known_joints(client: int) -> None:
    r2d2 = p.loadURDF("r2d2.urdf", physicsClientId=client)

    with pytest.raises(ValueError, match="no joint named 'elbow'") as info:
        joint_index(r2d2, "elbow", physics_client_id=client)

    assert "head_swivel" in str(info.value)
    assert "tobox" in str(info.value)
    # A link name is not a joint name.
    with pytest.raises(ValueError, match="no joint named 'head'"):
        joint_index(r2d2, "head", physics_client_id=client)


def test_lookup_uses_the_given_client() -> None:
    first = p.connect(p.DIRECT)
    second = p.connect(p.DIRECT)
    try:
        p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=second)
        kuka = p.loadURDF("kuka_iiwa/model.urdf", physicsClientId=second)
        assert resolve_joint_index(kuka, "lbr_iiwa_joint_2", physics_client_id=second) == 1
        with pytest.raises(ValueError, match="No body"):
            resolve_joint_index(kuka, "lbr_iiwa_joint_2", physics_client_id=first)
    finally:
        p.disconnect(second)
        p.disconnect(first)


# ----- calculate_offset_pose -------------------------------------------------------------


def test_offset_pose_approach_keeps_current_height_and_faces_target() -> None:
    pose = calculate_offset_pose([5.0, 0.0, 0.1], [0.0, 0.0, 0.3], offset=1.5)

    assert isinstance(pose, Pose)
    np.testing.assert_allclose(pose.position, [3.5, 0.0, 0.3], atol=1e-12)
    assert pose.yaw == pytest.approx(0.0, abs=1e-12)


def test_offset_pose_without_keep_height_uses_target_z() -> None:
    pose = calculate_offset_pose([5.0, 0.0, 0.1], [0.0, 0.0, 0.3], 0.3, keep_height=False)

    np.testing.assert_allclose(pose.position, [4.7, 0.0, 0.1], atol=1e-12)


def test_offset_pose_diagonal_from_other_side() -> None:
    pose = calculate_offset_pose([1.0, 1.0, 0.0], [4.0, 5.0, 0.2], offset=2.5)

    # Unit vector target -> current is (0.6, 0.8); facing back toward the target.
    np.testing.assert_allclose(pose.position, [2.5, 3.0, 0.2], atol=1e-12)
    assert pose.yaw == pytest.approx(math.atan2(-0.8, -0.6), abs=1e-12)
    np.testing.assert_allclose(pose.orientation[:2], [0.0, 0.0], atol=1e-12)


def test_offset_pose_zero_offset_is_at_target_still_facing_it() -> None:
    pose = calculate_offset_pose([0.0, 2.0, 0.5], [0.0, 0.0, 0.0], offset=0.0)

    np.testing.assert_allclose(pose.position, [0.0, 2.0, 0.0], atol=1e-12)
    assert pose.yaw == pytest.approx(math.pi / 2, abs=1e-12)


def test_offset_pose_coincident_xy_keeps_yaw_zero() -> None:
    pose = calculate_offset_pose([1.0, 2.0, 0.0], [1.0, 2.0, 1.0], offset=1.0)

    np.testing.assert_allclose(pose.position, [1.0, 2.0, 1.0], atol=1e-12)
    assert pose.yaw == 0.0


@pytest.mark.parametrize("offset", [-0.1, math.nan, math.inf, True, "1"])
def test_offset_pose_rejects_bad_offset(offset: object) -> None:
    with pytest.raises(ValueError, match="offset"):
        calculate_offset_pose([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], offset)  # type: ignore[arg-type]


def test_offset_pose_rejects_bad_positions() -> None:
    with pytest.raises(ValueError, match="target_position"):
        calculate_offset_pose([1.0, 0.0], [0.0, 0.0, 0.0], 1.0)
    with pytest.raises(ValueError, match="current_position"):
        calculate_offset_pose([1.0, 0.0, 0.0], 0.0, 1.0)  # type: ignore[arg-type]


# ----- grids -----------------------------------------------------------------------------


def test_world_to_grid_rounds_to_nearest_index_with_offset() -> None:
    assert world_to_grid([0.3, 0.6, 1.0], [0.1, 0.2, 0.5]) == [3, 3, 2]
    assert world_to_grid([2.4, -1.6, 0.0], [1.0, 1.0, 1.0], offset=[0.5, 0.5, 0.0]) == [2, -2, 0]
    assert world_to_grid([0.5, -0.5, 1.5], 1.0) == [1, 0, 2]  # halves round up
    assert all(type(i) is int for i in world_to_grid([0.3, 0.6, 1.0], 0.1))


def test_grid_to_world_and_round_trip() -> None:
    spacing, offset = [0.5, 2.0, 0.25], [1.0, -1.0, 0.1]

    world = grid_to_world([2, -3, 4], spacing, offset)

    assert world == pytest.approx([2.0, -7.0, 1.1])
    assert world_to_grid(world, spacing, offset) == [2, -3, 4]
    assert grid_to_world([1, 1, 1], 2.0) == [2.0, 2.0, 2.0]


def test_grid_2d_wrappers() -> None:
    # Three values, as the reference implementation returns from its 2-D wrappers.
    assert world_to_grid_2d([1.9, -0.9], [0.5, 0.3]) == [4, -3, 0]
    assert grid_to_world_2d([4, -3], [0.5, 0.3]) == pytest.approx([2.0, -0.9, 0.0])
    assert grid_to_world_2d([2, 3], 1.5) == pytest.approx([3.0, 4.5, 0.0])


def test_grid_conversions_take_2d_input() -> None:
    # Seed, tools.world_to_grid: "Convert world coordinates to grid indices (always 3D)".
    assert world_to_grid([1.2, 3.7], [1, 1]) == [1, 4, 0]
    assert grid_to_world([1, 4], [1, 1]) == [1.0, 4.0, 0.0]
    assert grid_to_world([1, 4], [0.5, 2.0], offset=[1.0, 1.0]) == [1.5, 9.0, 0.0]
    assert world_to_grid([1.6, 9.2], [0.5, 2.0], offset=[1.0, 1.0, 0.0]) == [1, 4, 0]


@pytest.mark.parametrize("spacing", [[0.0, 1.0, 1.0], [1.0, -1.0, 1.0], 0.0, [1.0, 1.0, 1.0, 1.0]])
def test_grid_rejects_bad_spacing(spacing: object) -> None:
    with pytest.raises(ValueError, match="spacing"):
        world_to_grid([0.0, 0.0, 0.0], spacing)  # type: ignore[arg-type]


def test_grid_rejects_bad_vectors() -> None:
    with pytest.raises(ValueError, match="pos"):
        world_to_grid([0.0], [1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="offset"):
        grid_to_world([0, 0, 0], 1.0, offset=[0.0, math.nan, 0.0])


def test_grid_execution_visits_x_then_y_then_z_as_the_reference() -> None:
    visits: list[tuple[list[int], list[float], str]] = []

    def record(grid_index: list[int], world_pos: list[float], tag: str) -> None:
        visits.append((grid_index, world_pos, tag))

    grid_execution([2, 2, 2], [1.0, 2.0, 3.0], [10.0, 0.0, 0.0], record, {"tag": "t"})

    # X outermost, Z fastest: the reference implementation's order.
    assert [v[0] for v in visits] == [
        [0, 0, 0],
        [0, 0, 1],
        [0, 1, 0],
        [0, 1, 1],
        [1, 0, 0],
        [1, 0, 1],
        [1, 1, 0],
        [1, 1, 1],
    ]
    assert visits[6][1] == [11.0, 2.0, 0.0]
    assert visits[7][1] == [11.0, 2.0, 3.0]
    assert {v[2] for v in visits} == {"t"}


def test_grid_execution_defaults_and_empty_axes() -> None:
    visits: list[tuple[list[int], list[float]]] = []

    def record(grid_index: list[int], world_pos: list[float]) -> None:
        visits.append((grid_index, world_pos))

    grid_execution(func=record)
    grid_execution([3, 0, 2], func=record)
    grid_execution([2, 2, 2])  # no callback: nothing to do, no error

    assert visits == [([0, 0, 0], [0.0, 0.0, 0.0])]


@pytest.mark.parametrize("grid_num", [[1, 1], [1, -1, 1], [1.5, 1, 1], [True, 1, 1]])
def test_grid_execution_rejects_bad_grid_num(grid_num: list[object]) -> None:
    with pytest.raises(ValueError, match="grid_num"):
        grid_execution(grid_num, func=lambda *a: None)  # type: ignore[arg-type]


# ----- find_nearest ----------------------------------------------------------------------


@dataclass
class Thing:
    name: str
    position: tuple[float, float, float]
    pickable: bool = True

    def get_pose(self) -> Pose:
        return Pose(self.position)


def test_find_nearest_picks_closest_within_radius() -> None:
    near, far = Thing("near", (1.0, 0.0, 0.0)), Thing("far", (3.0, 0.0, 0.0))

    assert find_nearest([far, near], [0.0, 0.0, 0.0], 5.0) is near
    assert find_nearest([far, near], [0.0, 0.0, 0.0], 0.5) is None
    assert find_nearest([], [0.0, 0.0, 0.0], 5.0) is None


def test_find_nearest_radius_is_inclusive() -> None:
    edge = Thing("edge", (2.0, 0.0, 0.0))

    assert find_nearest([edge], [0.0, 0.0, 0.0], 2.0) is edge


def test_find_nearest_predicate_and_exclude() -> None:
    me = Thing("me", (0.0, 0.0, 0.0))
    heavy = Thing("heavy", (0.5, 0.0, 0.0), pickable=False)
    box = Thing("box", (1.5, 0.0, 0.0))

    found = find_nearest(
        [me, heavy, box], [0.0, 0.0, 0.0], 2.0, predicate=lambda o: o.pickable, exclude=me
    )

    assert found is box
    assert find_nearest([me, heavy], [0.0, 0.0, 0.0], 2.0, exclude=me) is heavy


def test_find_nearest_use_2d_ignores_height() -> None:
    shelf = Thing("shelf", (1.0, 0.0, 5.0))
    floor = Thing("floor", (2.0, 0.0, 0.0))

    assert find_nearest([shelf, floor], [0.0, 0.0, 0.0], 10.0) is floor
    assert find_nearest([shelf, floor], [0.0, 0.0, 0.0], 10.0, use_2d=True) is shelf
    assert find_nearest([shelf], [0.0, 0.0, 0.0], 1.0, use_2d=True) is shelf


def test_find_nearest_ties_keep_iteration_order() -> None:
    a, b = Thing("a", (1.0, 0.0, 0.0)), Thing("b", (-1.0, 0.0, 0.0))

    assert find_nearest([a, b], [0.0, 0.0, 0.0], 2.0) is a
    assert find_nearest([b, a], [0.0, 0.0, 0.0], 2.0) is b


def test_find_nearest_accepts_generators_and_infinite_radius() -> None:
    things = [Thing(str(i), (float(i), 0.0, 0.0)) for i in range(5, 0, -1)]

    found = find_nearest((t for t in things), np.array([0.0, 0.0, 0.0]), math.inf)

    assert found is things[-1]


@pytest.mark.parametrize("radius", [-1.0, math.nan])
def test_find_nearest_rejects_bad_radius(radius: float) -> None:
    with pytest.raises(ValueError, match="search_radius"):
        find_nearest([], [0.0, 0.0, 0.0], radius)
