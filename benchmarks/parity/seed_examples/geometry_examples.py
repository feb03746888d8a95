"""Seed examples of pybullet_fleet.geometry (Path constructors, from_paths, visualize)."""

import numpy as np
import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.geometry import Path, Pose

T = Trace()


def n(path):
    return len(path.waypoints)


with T.probe("Path") as out:
    # Create from Pose list (recommended)
    path = Path([Pose.from_xyz(0, 0, 0), Pose.from_xyz(1, 0, 0), Pose.from_xyz(1, 1, 0)])
    # Create from positions
    path2 = Path.from_positions([[0, 0, 0], [1, 0, 0], [1, 1, 0]])
    # Create predefined shapes
    circle = Path.create_circle(center=[0, 0], radius=1.5)
    square = Path.create_square(center=[0, 0], side_length=2.0)
    out.update(
        path=n(path),
        path2=n(path2),
        circle=n(circle),
        square=n(square),
        circle_z=circle.waypoints[0].z,
    )
with T.probe("shapes") as out:
    rect = Path.create_rectangle(center=[0, 0, 1], width=3.0, height=2.0)
    tilted_rect = Path.create_rectangle(center=[0, 0, 1], width=3.0, height=2.0, rpy=[0.1, 0.2, 0])
    square = Path.create_square(center=[0, 0, 0], side_length=2.0)
    tilted_square = Path.create_square(center=[0, 0, 1], side_length=2.0, rpy=[0.1, 0.2, 0])
    ellipse = Path.create_ellipse(center=[0, 0, 0], radius_x=2.0, radius_y=1.0)
    tilted_ellipse = Path.create_ellipse(
        center=[0, 0, 1], radius_x=2.0, radius_y=1.0, rpy=[0, 0.3, 0]
    )
    circle = Path.create_circle(center=[0, 0, 0], radius=1.5)
    arc = Path.create_circle(center=[0, 0, 0], radius=1.5, start_angle=0, end_angle=np.pi)
    out["counts"] = [
        n(p)
        for p in (rect, tilted_rect, square, tilted_square, ellipse, tilted_ellipse, circle, arc)
    ]
    out["tilted_first"] = [round(v, 3) for v in tilted_rect.waypoints[0].position]
with T.probe("from_paths") as out:
    circle_arc = Path.create_circle(
        center=[0, 0, 0.5], radius=2.0, num_points=16, start_angle=0.0, end_angle=np.pi / 2
    )
    line = Path.from_positions([[1, 1, 0.5], [3, 1, 0.5]])
    full = Path.from_paths([circle_arc, line])
    out["n"] = n(full)
    out["distance"] = round(full.get_total_distance(), 4)
sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
with T.probe("visualize") as out:
    # Just show path lines
    path = Path.create_circle(center=[0, 0, 0.5], radius=2.0)
    ids = call_safely(path.visualize, line_color=[1, 0, 0])
    out["lines"] = ids if isinstance(ids, dict) else len(ids)
    # Show path with waypoint orientations
    ids = call_safely(path.visualize, show_waypoints=True, show_axes=True)
    out["waypoints"] = ids if isinstance(ids, dict) else len(ids)
    path = Path.create_square(center=[0, 0, 1], side_length=2.0, rpy=[0.1, 0.2, 0])
    debug_ids = call_safely(path.visualize_waypoints, axis_length=0.5)
    out["visualize_waypoints"] = debug_ids if isinstance(debug_ids, dict) else len(debug_ids)
pybullet.disconnect(physicsClientId=sim.client)
T.dump()
