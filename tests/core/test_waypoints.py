"""Path: validation, shape constructors and their orientation convention, combining, drawing."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pybullet as p
import pytest

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.quaternions import quat_from_euler, quat_multiply, rotate_vector
from fleet_async.core.geometry.waypoints import Path

S = math.sqrt(0.5)


@pytest.fixture
def client() -> Iterator[int]:
    """A headless PyBullet client, disconnected afterwards."""
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(cid)


def line(n: int) -> Path:
    return Path.from_positions([[i, 0, 0] for i in range(n)])


def heading(pose: Pose) -> np.ndarray:
    return rotate_vector([1, 0, 0], pose.orientation)


def intrinsic_xyz(rpy):
    """The plane frame of the shape constructors: intrinsic X-Y-Z (the reference's tilt)."""
    roll, pitch, yaw = rpy
    return quat_multiply(
        quat_multiply(quat_from_euler(roll, 0, 0), quat_from_euler(0, pitch, 0)),
        quat_from_euler(0, 0, yaw),
    )


def assert_faces_next(path: Path) -> None:
    """Each waypoint's X axis points at the next one (the last along the last chord)."""
    pts = [wp.position for wp in path]
    for i, wp in enumerate(path):
        if i + 1 < len(pts):
            a, b = pts[i], pts[i + 1]
        else:
            a, b = pts[i - 1], pts[i]
        chord = (b - a) / np.linalg.norm(b - a)
        np.testing.assert_allclose(heading(wp), chord, atol=1e-12)


# --- construction and validation ------------------------------------------------------


def test_path_holds_given_poses_in_order():
    poses = [Pose.from_xyz(0, 0, 0), Pose.from_xyz(1, 0, 0)]
    path = Path(poses)
    poses.append(Pose.from_xyz(2, 0, 0))  # the list is copied, the poses are shared
    assert len(path) == 2
    assert path.waypoints[1] is poses[1]


def test_empty_path_is_allowed():
    path = Path([])
    assert len(path) == 0 and path.get_total_distance() == 0.0 and list(path) == []


def test_non_pose_waypoint_raises_naming_index():
    with pytest.raises(
        TypeError, match=r"^Path\.waypoints\[1\]: expected a Pose, got \[1, 0, 0\] \(list\) in \["
    ):
        Path([Pose.from_xyz(0, 0, 0), [1, 0, 0]])


def test_numbers_as_waypoints_are_named_as_numbers():
    with pytest.raises(TypeError, match=r"got \(3, 0, 0\) \(numbers: .*Pose\.from_xyz"):
        Path((3, 0, 0))


@pytest.mark.parametrize("bad", [Pose.from_xyz(0, 0, 0), 5, None])
def test_non_iterable_waypoints_raise(bad):
    with pytest.raises(TypeError, match=r"^Path\.waypoints: expected an iterable of Pose"):
        Path(bad)


def test_from_positions_shares_one_normalised_orientation():
    path = Path.from_positions(
        [[0, 0, 0], (1, 2, 3), np.array([4, 5, 6])], orientation=[0, 0, 2, 2]
    )
    assert [wp.position.tolist() for wp in path] == [[0, 0, 0], [1, 2, 3], [4, 5, 6]]
    for wp in path:
        np.testing.assert_allclose(wp.orientation, [0, 0, S, S], atol=1e-15)
    assert path[0].orientation is not path[1].orientation
    assert Path.from_positions([[1, 1, 1]])[0].orientation.tolist() == [0, 0, 0, 1]


def test_from_positions_errors_name_the_index_or_orientation():
    with pytest.raises(ValueError, match=r"^positions\[1\]: Pose\.position: expected 3 finite"):
        Path.from_positions([[0, 0, 0], [1, 2], [3, 4, 5]])
    with pytest.raises(ValueError, match=r"^Pose\.orientation: zero-norm"):
        Path.from_positions([[0, 0, 0]], orientation=[0, 0, 0, 0])


# --- rectangles and squares -----------------------------------------------------------


def test_rectangle_corners_are_ccw_and_closed():
    # As the reference implementation: the first corner is repeated, so a patrol comes back.
    rect = Path.create_rectangle(center=[1, 2, 3], width=4.0, height=2.0)
    corners = [wp.position.tolist() for wp in rect]
    assert corners == [[-1, 1, 3], [3, 1, 3], [3, 3, 3], [-1, 3, 3], [-1, 1, 3]]
    yaws = [wp.yaw for wp in rect]
    np.testing.assert_allclose(
        yaws, [0, math.pi / 2, math.pi, -math.pi / 2, -math.pi / 2], atol=1e-15
    )
    assert rect.get_total_distance() == 12.0  # four sides
    assert_faces_next(rect)


def test_rectangle_with_2d_center_sits_at_z_zero():
    rect = Path.create_rectangle(center=[5, 5], width=2.0, height=2.0)
    assert [wp.z for wp in rect] == [0.0] * 5
    assert rect[0].position.tolist() == [4.0, 4.0, 0.0]


def test_tilted_rectangle_lies_in_its_plane_with_z_along_the_normal():
    rpy = [0.1, 0.2, 0.3]
    center = np.array([0.0, 0.0, 1.0])
    rect = Path.create_rectangle(center=center, width=3.0, height=2.0, rpy=rpy)
    frame = intrinsic_xyz(rpy)
    normal = rotate_vector([0, 0, 1], frame)
    for wp in rect:
        assert float((wp.position - center) @ normal) == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(rotate_vector([0, 0, 1], wp.orientation), normal, atol=1e-12)
    first_local = rotate_vector([-1.5, -1.0, 0.0], frame) + center
    np.testing.assert_allclose(rect[0].position, first_local, atol=1e-12)
    np.testing.assert_allclose(rect[0].orientation, frame, atol=1e-15)  # heading 0
    assert_faces_next(rect)


def test_tilted_shapes_land_where_the_reference_puts_them():
    # The first corner of the reference's tilted-rectangle example (measured on pybullet_fleet
    # 0.8.0): roll, then pitch about the new Y axis.
    rect = Path.create_rectangle(center=[0, 0, 1], width=3.0, height=2.0, rpy=[0.1, 0.2, 0])
    np.testing.assert_allclose(rect[0].position, [-1.470, -1.025, 1.197], atol=1e-3)


def test_square_is_rectangle_with_equal_sides():
    square = Path.create_square(center=[0, 0, 1], side_length=2.0, rpy=[0.1, 0.2, 0])
    assert square == Path.create_rectangle([0, 0, 1], 2.0, 2.0, rpy=[0.1, 0.2, 0])
    assert len(square) == 5 and square[-1].position.tolist() == square[0].position.tolist()


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"width": 0.0, "height": 1.0}, "width"),
        ({"width": 1.0, "height": -2.0}, "height"),
        ({"width": math.nan, "height": 1.0}, "width"),
        ({"width": "1", "height": 1.0}, "width"),
    ],
)
def test_rectangle_rejects_non_positive_sizes(kwargs, field):
    with pytest.raises(ValueError, match=rf"^{field}: expected a positive finite number"):
        Path.create_rectangle(center=[0, 0], **kwargs)


def test_shape_rejects_bad_center_rpy_and_side():
    with pytest.raises(ValueError, match=r"^center: expected 3 finite numbers"):
        Path.create_square(center=[0], side_length=1.0)
    with pytest.raises(ValueError, match=r"^center: expected 2 finite numbers \[x, y\]"):
        Path.create_square(center=[0, math.inf], side_length=1.0)
    with pytest.raises(ValueError, match=r"^rpy: expected 3 finite numbers"):
        Path.create_square(center=[0, 0], side_length=1.0, rpy=[0, 0])
    with pytest.raises(ValueError, match=r"^side_length: expected a positive finite number"):
        Path.create_square(center=[0, 0], side_length=0)


# --- ellipses and circles -------------------------------------------------------------


def test_full_ellipse_is_evenly_spaced_and_ends_at_the_start():
    # num_points steps, num_points + 1 waypoints, as the reference implementation.
    ellipse = Path.create_ellipse(center=[1, 2, 0.5], radius_x=2.0, radius_y=1.0, num_points=8)
    assert len(ellipse) == 9
    for k, wp in enumerate(ellipse):
        a = 2 * math.pi * k / 8
        np.testing.assert_allclose(
            wp.position, [1 + 2 * math.cos(a), 2 + math.sin(a), 0.5], atol=1e-15
        )
    assert ellipse[-1].position.tolist() == ellipse[0].position.tolist()
    assert_faces_next(ellipse)


def test_ellipse_arc_includes_both_ends_and_keeps_last_heading():
    arc = Path.create_ellipse(
        center=[0, 0], radius_x=2.0, radius_y=1.0, num_points=4, start_angle=0.0, end_angle=math.pi
    )
    assert len(arc) == 5
    np.testing.assert_allclose(arc[0].position, [2, 0, 0], atol=1e-15)
    np.testing.assert_allclose(arc[-1].position, [-2, 0, 0], atol=1e-15)
    np.testing.assert_allclose(arc[2].position, [0, 1, 0], atol=1e-15)
    assert_faces_next(arc)
    np.testing.assert_allclose(arc[-1].orientation, arc[-2].orientation, atol=1e-15)


def test_negative_span_runs_clockwise():
    loop = Path.create_circle(center=[0, 0], radius=1.0, num_points=4, end_angle=-2 * math.pi)
    positions = [wp.position.tolist() for wp in loop]
    np.testing.assert_allclose(
        positions, [[1, 0, 0], [0, -1, 0], [-1, 0, 0], [0, 1, 0], [1, 0, 0]], atol=1e-15
    )
    assert_faces_next(loop)


def test_tilted_circle_lies_in_plane_and_faces_along_it():
    rpy = [0.0, 0.3, 0.0]
    circle = Path.create_circle(center=[0, 0, 1], radius=1.5, num_points=12, rpy=rpy)
    normal = rotate_vector([0, 0, 1], intrinsic_xyz(rpy))
    for wp in circle:
        offset = wp.position - np.array([0, 0, 1])
        assert np.linalg.norm(offset) == pytest.approx(1.5, abs=1e-12)
        assert float(offset @ normal) == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(rotate_vector([0, 0, 1], wp.orientation), normal, atol=1e-12)
    assert_faces_next(circle)


def test_circle_is_ellipse_with_equal_radii_and_polyline_length():
    circle = Path.create_circle(center=[0, 0, 0], radius=1.5)
    assert circle == Path.create_ellipse([0, 0, 0], 1.5, 1.5)
    assert len(circle) == 17
    chord = 2 * 1.5 * math.sin(math.pi / 16)
    assert circle.get_total_distance() == pytest.approx(16 * chord, rel=1e-14)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"radius_x": 0.0, "radius_y": 1.0}, r"^radius_x: expected a positive"),
        ({"radius_x": 1.0, "radius_y": -1.0}, r"^radius_y: expected a positive"),
        ({"radius_x": 1.0, "radius_y": 1.0, "num_points": 0}, r"^num_points: expected an int"),
        ({"radius_x": 1.0, "radius_y": 1.0, "num_points": 4.0}, r"^num_points: expected an int"),
        ({"radius_x": 1.0, "radius_y": 1.0, "end_angle": 0.0}, r"^end_angle: expected a finite"),
        ({"radius_x": 1.0, "radius_y": 1.0, "end_angle": math.inf}, r"^end_angle: expected"),
    ],
)
def test_ellipse_rejects_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Path.create_ellipse(center=[0, 0], **kwargs)


def test_circle_rejects_bad_radius_by_name():
    with pytest.raises(ValueError, match=r"^radius: expected a positive finite number, got -1"):
        Path.create_circle(center=[0, 0], radius=-1)


# --- combining, sequence protocol, length ---------------------------------------------


def test_append_mutates_and_shares_poses():
    a, b = line(2), line(3)
    a.append(b)
    assert len(a) == 5 and len(b) == 3
    assert a[2] is b[0]
    with pytest.raises(TypeError, match="other: expected Path"):
        a.append([Pose.from_xyz(0, 0, 0)])


def test_add_does_not_mutate():
    a, b = line(2), line(3)
    c = a + b
    assert (len(a), len(b), len(c)) == (2, 3, 5)
    assert c.waypoints == a.waypoints + b.waypoints
    with pytest.raises(TypeError):
        a + 1  # type: ignore[operator]


def test_from_paths_concatenates_in_order_and_checks_items():
    arc = Path.create_circle(center=[0, 0, 0.5], radius=2.0, end_angle=math.pi / 2)
    tail = Path.from_positions([[1, 1, 0.5], [3, 1, 0.5]])
    full = Path.from_paths([arc, tail])
    assert len(full) == len(arc) + 2
    assert full[0] is arc[0] and full[-1] is tail[-1]
    assert Path.from_paths([]) == Path([])
    with pytest.raises(TypeError, match=r"^paths\[1\]: expected Path"):
        Path.from_paths([arc, [Pose.from_xyz(0, 0, 0)]])


def test_sequence_protocol():
    path = line(4)
    assert [wp.x for wp in path] == [0.0, 1.0, 2.0, 3.0]
    assert path[-1].x == 3.0
    middle = path[1:3]
    assert isinstance(middle, Path) and [wp.x for wp in middle] == [1.0, 2.0]
    with pytest.raises(IndexError):
        path[4]


def test_equality_and_repr():
    assert line(2) == line(2)
    assert line(2) != line(3)
    assert line(2) != "path"
    assert repr(Path([Pose.from_xyz(1, 0, 0)])) == (
        "Path([Pose(position=[1.0, 0.0, 0.0], orientation=[0.0, 0.0, 0.0, 1.0])])"
    )


def test_total_distance_sums_segments():
    path = Path.from_positions([[0, 0, 0], [3, 4, 0], [3, 4, 12]])
    assert path.get_total_distance() == 17.0
    assert line(1).get_total_distance() == 0.0


# --- drawing (PyBullet DIRECT accepts debug items and returns -1 ids) -----------------


def test_visualize_counts_items(client):
    path = line(4)
    lines_only = path.visualize(physics_client_id=client)
    assert isinstance(lines_only, list) and len(lines_only) == 3
    assert all(isinstance(i, int) for i in lines_only)
    everything = path.visualize(line_color=[1, 0, 0], show_waypoints=True, physics_client_id=client)
    assert len(everything) == 3 + 4 * 3 + 1
    axes = path.visualize(show_lines=False, show_axes=True, lifetime=1.0, physics_client_id=client)
    assert len(axes) == 12
    points = path.visualize(show_lines=False, show_points=True, physics_client_id=client)
    assert len(points) == 1


def test_visualize_waypoints_counts_items(client):
    path = Path.create_square(center=[0, 0, 1], side_length=2.0, rpy=[0.1, 0.2, 0])
    assert len(path.visualize_waypoints(axis_length=0.5, physics_client_id=client)) == 16
    assert path.visualize_waypoints(show_axes=False, show_points=False) == []
    assert Path([]).visualize(show_waypoints=True, physics_client_id=client) == []
