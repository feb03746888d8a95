"""Pose / Path helpers: from_yaw, from_euler, create_circle / square / rectangle waypoints."""

import math

from parity_trace import Trace, angle, call_safely
from pybullet_fleet.geometry import Path, Pose

T = Trace()


def wp(path):
    return [[round(w.x, 3), round(w.y, 3), round(w.z, 3), angle(w.yaw)] for w in path.waypoints]


with T.probe("pose") as out:
    out["from_yaw"] = call_safely(lambda: Pose.from_yaw(1, 2, 0, math.pi / 2).as_tuple())
    out["from_euler"] = Pose.from_euler(1, 2, 3, roll=0.1, pitch=0.2, yaw=0.3).as_euler()
    out["default_orientation"] = Pose(position=[1, 2, 3]).orientation
    out["from_pybullet"] = Pose.from_pybullet((1, 2, 3), (0, 0, 0, 1)).position
    out["position_type"] = type(Pose.from_xyz(1, 2, 3).position).__name__
    out["eq"] = call_safely(lambda: Pose.from_xyz(1, 2, 3) == Pose.from_xyz(1, 2, 3))
    out["repr"] = repr(Pose.from_xyz(1, 2, 3))
with T.probe("path") as out:
    out["circle_8"] = wp(Path.create_circle(center=[0, 0, 0], radius=1.0, num_points=8))
    out["circle_default_len"] = len(Path.create_circle(center=[0, 0, 0], radius=1.5).waypoints)
    out["arc"] = wp(
        Path.create_circle(
            center=[0, 0, 0], radius=1.5, num_points=4, start_angle=0, end_angle=math.pi
        )
    )
    out["square"] = wp(Path.create_square(center=[0, 0, 0], side_length=2.0))
    out["rectangle"] = wp(Path.create_rectangle(center=[0, 0, 1], width=3.0, height=2.0))
    out["ellipse_4"] = wp(
        Path.create_ellipse(center=[0, 0, 0], radius_x=2.0, radius_y=1.0, num_points=4)
    )
    out["from_positions"] = wp(Path.from_positions([[0, 0, 0], [1, 0, 0], [1, 1, 0]]))
    out["total_distance"] = Path.from_positions([[0, 0, 0], [3, 4, 0]]).get_total_distance()
    p1, p2 = Path.from_positions([[0, 0, 0]]), Path.from_positions([[1, 0, 0]])
    out["add"] = call_safely(lambda: len((p1 + p2).waypoints))
    out["from_paths"] = len(Path.from_paths([p1, p2]).waypoints)
    p1.append(p2)
    out["append_mutates"] = len(p1.waypoints)
    out["len"] = call_safely(lambda: len(p1))
T.dump()
