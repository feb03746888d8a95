"""Path: an ordered sequence of Pose waypoints, with shape constructors and debug drawing.

Positions are in metres, angles in radians, quaternions ``(x, y, z, w)`` like PyBullet.
"""

from __future__ import annotations

import itertools
import math
import numbers
from collections.abc import Iterable, Iterator, Sequence
from typing import overload

import numpy as np

from fleet_async.core.base.reprs import short_repr
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.quaternions import quat_from_euler, quat_multiply, quat_to_rot_matrix

__all__ = ["Path"]

_DEFAULT_LINE_COLOR = (0.0, 0.6, 1.0)
_POINT_COLOR = (1.0, 0.8, 0.0)
_AXIS_COLORS = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
# PyBullet draws debug points with a size in pixels; point_size is given in metres.
_POINT_PIXELS_PER_METRE = 100.0


def _positive(value: float, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name}: expected a positive finite number, got {value!r}")
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name}: expected a positive finite number, got {value!r}")
    return float(value)


def _finite_floats(value: object, n: int, name: str, layout: str) -> list[float]:
    arr = np.asarray(value)
    if arr.shape == (n,) and arr.dtype.kind in "iuf":
        floats = arr.astype(np.float64).tolist()
        if all(map(math.isfinite, floats)):
            return floats
    raise ValueError(f"{name}: expected {n} finite numbers {layout}, got {value!r}")


def _center3(center: Sequence[float] | np.ndarray) -> np.ndarray:
    """Return ``[x, y, z]`` for a 3-D center or ``[x, y, 0]`` for a 2-D one."""
    if np.shape(center) == (2,):
        return np.array([*_finite_floats(center, 2, "center", "[x, y]"), 0.0])
    return np.array(_finite_floats(center, 3, "center", "[x, y] or [x, y, z]"))


class Path:
    """An ordered sequence of ``Pose`` waypoints.

    A Path holds references to its Poses: combining paths shares Pose objects, never copies
    them. Shape constructors lay points out in a local XY plane, rotate that plane by ``rpy``
    (PyBullet Euler convention) and translate it to ``center``. Each shape waypoint is
    oriented as ``q_rpy * q_z(heading)``, where ``heading`` is the in-plane direction of the
    chord to the next waypoint, so the waypoint's X axis points along the path and its Z axis
    is the plane's normal. Closed shapes (rectangles, full ellipses) do not repeat their first
    waypoint; their last waypoint faces the first. The last waypoint of an open arc keeps the
    heading of the chord that reaches it.

    Example:
        >>> square = Path.create_square(center=[0, 0], side_length=2.0)
        >>> len(square), square.get_total_distance()
        (4, 6.0)

    Attributes:
        waypoints: The waypoints, in travel order.
    """

    __slots__ = ("waypoints",)

    waypoints: list[Pose]

    def __init__(self, waypoints: Iterable[Pose]) -> None:
        """Create a path.

        Raises:
            TypeError: If ``waypoints`` is not iterable or an item is not a Pose (the message
                names its index).
        """
        if isinstance(waypoints, Pose) or not isinstance(waypoints, Iterable):
            raise TypeError(
                f"Path.waypoints: expected an iterable of Pose, got {short_repr(waypoints)} "
                f"({type(waypoints).__name__})"
            )
        items = list(waypoints)
        if items and all(isinstance(v, numbers.Real) for v in items):
            raise TypeError(
                f"Path.waypoints: expected an iterable of Pose, got {short_repr(waypoints)} "
                "(numbers: for one position give [Pose.from_xyz(x, y, z)], for several "
                "Path.from_positions([[x, y, z], ...]))"
            )
        for i, waypoint in enumerate(items):
            if not isinstance(waypoint, Pose):
                raise TypeError(
                    f"Path.waypoints[{i}]: expected a Pose, got {short_repr(waypoint)} "
                    f"({type(waypoint).__name__}) in {short_repr(waypoints)}"
                )
        self.waypoints = items

    @classmethod
    def from_positions(
        cls,
        positions: Iterable[Sequence[float] | np.ndarray],
        orientation: Sequence[float] | np.ndarray | None = None,
    ) -> Path:
        """Create a path from ``[x, y, z]`` positions in metres sharing one orientation.

        Args:
            positions: Waypoint positions in travel order.
            orientation: Quaternion ``[x, y, z, w]`` for every waypoint; None means no rotation.

        Raises:
            ValueError: If the orientation is invalid, or a position is (naming its index).
        """
        origin = (0.0, 0.0, 0.0)
        quat = (Pose(origin) if orientation is None else Pose(origin, orientation)).orientation
        waypoints = []
        for i, position in enumerate(positions):
            try:
                pose = Pose(position)
            except ValueError as err:
                raise ValueError(f"positions[{i}]: {err}") from err
            pose.orientation = quat.copy()
            waypoints.append(pose)
        return cls(waypoints)

    @classmethod
    def create_rectangle(
        cls,
        center: Sequence[float] | np.ndarray,
        width: float,
        height: float,
        rpy: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> Path:
        """Create a closed rectangular path through its corners, counter-clockwise about the
        plane's normal.

        Corners start at local ``(-width/2, -height/2)``; the first corner is repeated at the
        end (5 waypoints), so a robot following the path comes back to where it started, as
        in the reference implementation.

        Args:
            center: ``[x, y, z]`` (or ``[x, y]`` with z = 0) in metres, world frame.
            width: Side length along the local X axis, metres.
            height: Side length along the local Y axis, metres.
            rpy: Roll, pitch, yaw of the rectangle's plane in radians (see ``_planar``); its
                normal is local Z.

        Raises:
            ValueError: If a size is not positive or ``center``/``rpy`` is malformed.
        """
        hw = 0.5 * _positive(width, "width")
        hh = 0.5 * _positive(height, "height")
        corners = [(-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh), (-hw, -hh)]
        return cls._planar(center, corners, rpy)

    @classmethod
    def create_square(
        cls,
        center: Sequence[float] | np.ndarray,
        side_length: float,
        rpy: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> Path:
        """Create a square path: ``create_rectangle`` with width == height == ``side_length``."""
        side = _positive(side_length, "side_length")
        return cls.create_rectangle(center, side, side, rpy)

    @classmethod
    def create_ellipse(
        cls,
        center: Sequence[float] | np.ndarray,
        radius_x: float,
        radius_y: float,
        num_points: int = 16,
        rpy: Sequence[float] = (0.0, 0.0, 0.0),
        start_angle: float = 0.0,
        end_angle: float = 2 * math.pi,
    ) -> Path:
        """Create waypoints on an elliptical arc from start to end angle, both included.

        ``num_points`` is the number of equal steps of the parameter angle, so the path has
        ``num_points + 1`` waypoints (as the reference implementation makes them): a full turn
        ends where it started, so a robot following it comes back. The path runs
        counter-clockwise when ``end_angle > start_angle``.

        Args:
            center: ``[x, y, z]`` (or ``[x, y]`` with z = 0) in metres, world frame.
            radius_x: Semi-axis along local X, metres.
            radius_y: Semi-axis along local Y, metres.
            num_points: Number of steps along the arc, at least 1.
            rpy: Roll, pitch, yaw of the ellipse's plane in radians (see ``_planar``).
            start_angle: Start parameter angle in the local XY plane, radians.
            end_angle: End parameter angle in the local XY plane, radians.

        Raises:
            ValueError: On a non-positive radius, fewer than 1 step, or equal angles.
        """
        rx, ry = _positive(radius_x, "radius_x"), _positive(radius_y, "radius_y")
        if isinstance(num_points, bool) or not isinstance(num_points, int) or num_points < 1:
            raise ValueError(f"num_points: expected an integer >= 1, got {num_points!r}")
        span = float(end_angle) - float(start_angle)
        if not math.isfinite(span) or span == 0.0:
            raise ValueError(
                f"end_angle: expected a finite angle other than start_angle, got {end_angle!r}"
            )
        angles = [start_angle + span * k / num_points for k in range(num_points + 1)]
        points = [(rx * math.cos(a), ry * math.sin(a)) for a in angles]
        if math.isclose(abs(span), 2.0 * math.pi, rel_tol=0.0, abs_tol=1e-9):
            points[-1] = points[0]  # a full turn closes exactly
        return cls._planar(center, points, rpy)

    @classmethod
    def create_circle(
        cls,
        center: Sequence[float] | np.ndarray,
        radius: float,
        num_points: int = 16,
        rpy: Sequence[float] = (0.0, 0.0, 0.0),
        start_angle: float = 0.0,
        end_angle: float = 2 * math.pi,
    ) -> Path:
        """Create a circular arc: ``create_ellipse`` with both radii equal to ``radius``."""
        r = _positive(radius, "radius")
        return cls.create_ellipse(center, r, r, num_points, rpy, start_angle, end_angle)

    @classmethod
    def _planar(
        cls,
        center: Sequence[float] | np.ndarray,
        points: list[tuple[float, float]],
        rpy: Sequence[float],
    ) -> Path:
        """Waypoints at planar ``points`` in a tilted plane, each facing the next one.

        The plane's frame is ``rpy`` as intrinsic X-Y-Z rotations (roll about X, then pitch
        about the new Y, then yaw about the newest Z), as the reference implementation tilts
        its shapes; ``Pose.from_euler`` uses PyBullet's extrinsic convention instead. The last
        waypoint keeps the heading of the segment that reaches it.
        """
        origin = _center3(center)
        roll, pitch, yaw = _finite_floats(rpy, 3, "rpy", "[roll, pitch, yaw]")
        frame = quat_multiply(
            quat_multiply(quat_from_euler(roll, 0.0, 0.0), quat_from_euler(0.0, pitch, 0.0)),
            quat_from_euler(0.0, 0.0, yaw),
        )
        r = quat_to_rot_matrix(frame)
        ex = np.array([r[0], r[3], r[6]])
        ey = np.array([r[1], r[4], r[7]])
        n = len(points)
        waypoints = []
        for i, (px, py) in enumerate(points):
            a, b = (i, i + 1) if i + 1 < n else (i - 1, i)
            heading = math.atan2(points[b][1] - points[a][1], points[b][0] - points[a][0])
            turn = (0.0, 0.0, math.sin(0.5 * heading), math.cos(0.5 * heading))
            position = origin + px * ex + py * ey
            waypoints.append(Pose.from_arrays_unchecked(position, quat_multiply(frame, turn)))
        return cls(waypoints)

    @classmethod
    def from_paths(cls, paths: Iterable[Path]) -> Path:
        """Concatenate paths, in order, into a new Path.

        Raises:
            TypeError: If an item is not a Path (the message names its index).
        """
        waypoints: list[Pose] = []
        for i, path in enumerate(paths):
            if not isinstance(path, Path):
                raise TypeError(f"paths[{i}]: expected Path, got {path!r}")
            waypoints.extend(path.waypoints)
        return cls(waypoints)

    def append(self, other: Path) -> None:
        """Append ``other``'s waypoints in place (``self + other`` does not mutate)."""
        if not isinstance(other, Path):
            raise TypeError(f"other: expected Path, got {other!r}")
        self.waypoints.extend(other.waypoints)

    def __add__(self, other: Path) -> Path:
        if not isinstance(other, Path):
            return NotImplemented
        return Path(self.waypoints + other.waypoints)

    def __len__(self) -> int:
        return len(self.waypoints)

    def __iter__(self) -> Iterator[Pose]:
        return iter(self.waypoints)

    @overload
    def __getitem__(self, index: int) -> Pose: ...
    @overload
    def __getitem__(self, index: slice) -> Path: ...
    def __getitem__(self, index: int | slice) -> Pose | Path:
        """Return one waypoint, or a new Path for a slice."""
        if isinstance(index, slice):
            return Path(self.waypoints[index])
        return self.waypoints[index]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Path):
            return NotImplemented
        return self.waypoints == other.waypoints

    __hash__ = None  # type: ignore[assignment]  # mutable, compared by value

    def __repr__(self) -> str:
        return f"Path({self.waypoints!r})"

    def get_total_distance(self) -> float:
        """Return the length in metres of the polyline through the waypoints, in order."""
        pts = [wp.position.tolist() for wp in self.waypoints]
        return math.fsum(math.dist(a, b) for a, b in itertools.pairwise(pts))

    def visualize(
        self,
        show_lines: bool = True,
        line_color: Sequence[float] | None = None,
        line_width: float = 2.0,
        show_waypoints: bool = False,
        show_axes: bool = False,
        axis_length: float = 0.3,
        show_points: bool = False,
        point_size: float = 0.05,
        lifetime: float = 0.0,
        physics_client_id: int = 0,
    ) -> list[int]:
        """Draw the path with PyBullet debug lines, optionally with waypoint markers.

        Args:
            show_lines: Draw a line between consecutive waypoints.
            line_color: RGB in ``[0, 1]`` for the lines; None for the default light blue.
            line_width: Line width in pixels.
            show_waypoints: Shorthand for ``show_axes=True, show_points=True``.
            show_axes: Draw each waypoint's X (red), Y (green), Z (blue) axes.
            axis_length: Axis length in metres.
            show_points: Mark each waypoint position with a debug point.
            point_size: Marker size in metres, drawn at 100 px per metre.
            lifetime: Seconds the items stay; 0 keeps them until removed or reset.
            physics_client_id: PyBullet client to draw in.

        Returns:
            The debug item ids, for ``pybullet.removeUserDebugItem``.
        """
        import pybullet as p  # deferred: importing pybullet prints a banner

        ids: list[int] = []
        if show_lines:
            color = list(_DEFAULT_LINE_COLOR if line_color is None else line_color)
            for a, b in itertools.pairwise(self.waypoints):
                ids.append(
                    p.addUserDebugLine(
                        a.position.tolist(),
                        b.position.tolist(),
                        lineColorRGB=color,
                        lineWidth=line_width,
                        lifeTime=lifetime,
                        physicsClientId=physics_client_id,
                    )
                )
        if show_waypoints or show_axes or show_points:
            ids += self.visualize_waypoints(
                show_axes=show_waypoints or show_axes,
                axis_length=axis_length,
                show_points=show_waypoints or show_points,
                point_size=point_size,
                lifetime=lifetime,
                physics_client_id=physics_client_id,
            )
        return ids

    def visualize_waypoints(
        self,
        show_axes: bool = True,
        axis_length: float = 0.3,
        show_points: bool = True,
        point_size: float = 0.05,
        lifetime: float = 0.0,
        physics_client_id: int = 0,
    ) -> list[int]:
        """Draw each waypoint's frame axes and position marker with PyBullet debug items.

        Args:
            show_axes: Draw 3 lines per waypoint: X red, Y green, Z blue.
            axis_length: Axis length in metres.
            show_points: Draw one debug point per waypoint (a single debug item).
            point_size: Marker size in metres, drawn at 100 px per metre.
            lifetime: Seconds the items stay; 0 keeps them until removed or reset.
            physics_client_id: PyBullet client to draw in.

        Returns:
            The debug item ids: axis lines first, then the points item.
        """
        import pybullet as p  # deferred: importing pybullet prints a banner

        ids: list[int] = []
        if show_axes:
            for wp in self.waypoints:
                r = quat_to_rot_matrix(wp.orientation)
                start = wp.position.tolist()
                for k, color in enumerate(_AXIS_COLORS):
                    axis = (r[k], r[3 + k], r[6 + k])
                    end = [s + axis_length * a for s, a in zip(start, axis, strict=True)]
                    ids.append(
                        p.addUserDebugLine(
                            start,
                            end,
                            lineColorRGB=list(color),
                            lifeTime=lifetime,
                            physicsClientId=physics_client_id,
                        )
                    )
        if show_points and self.waypoints:
            ids.append(
                p.addUserDebugPoints(
                    [wp.position.tolist() for wp in self.waypoints],
                    [list(_POINT_COLOR)] * len(self.waypoints),
                    pointSize=max(1.0, point_size * _POINT_PIXELS_PER_METRE),
                    lifeTime=lifetime,
                    physicsClientId=physics_client_id,
                )
            )
        return ids
