"""Poses, paths, quaternion helpers and kinematic-limit helpers.

The reference API's ``geometry`` module: a thin facade over the modules of the core that own
these names, so a pybullet_fleet script ports by renaming its import
(``pybullet_fleet.geometry`` becomes ``fleet_async.geometry``). Nothing in fleet_async imports
this module.
"""

from __future__ import annotations

from fleet_async.core.geometry.limits import (
    ScalarOrAxes,
    as_axes,
    clamp_vec_to_limit,
    is_scalar,
    projected_axis_limit,
)
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.quaternions import (
    Quat,
    SlerpPrecomp,
    quat_angle_between,
    quat_from_rotvec,
    quat_multiply,
    quat_slerp,
    quat_slerp_batch,
    quat_slerp_precompute,
    quat_to_rot_matrix,
    rotate_vector,
)
from fleet_async.core.geometry.waypoints import Path

__all__ = [
    "Path",
    "Pose",
    "Quat",
    "ScalarOrAxes",
    "SlerpPrecomp",
    "as_axes",
    "clamp_vec_to_limit",
    "is_scalar",
    "projected_axis_limit",
    "quat_angle_between",
    "quat_from_rotvec",
    "quat_multiply",
    "quat_slerp",
    "quat_slerp_batch",
    "quat_slerp_precompute",
    "quat_to_rot_matrix",
    "rotate_vector",
]
