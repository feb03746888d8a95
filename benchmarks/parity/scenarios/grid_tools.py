"""tools: world_to_grid / grid_to_world (2D and 3D input, rounding), offsets, small helpers."""

import math

from parity_trace import Trace, call_safely
from pybullet_fleet.tools import (
    body_to_world_velocity_2d,
    calculate_offset_pose,
    grid_to_world,
    grid_to_world_2d,
    normalize_vector_param,
    world_to_grid,
    world_to_grid_2d,
)

T = Trace()
with T.probe("world_to_grid") as out:
    out["3d"] = call_safely(world_to_grid, [1.2, 3.7, 0.0], [1.0, 1.0, 1.0])
    out["3d_offset"] = call_safely(world_to_grid, [1.2, 3.7, 0.0], [1.0, 1.0, 1.0], [0.5, 0.5, 0.0])
    out["2d_input"] = call_safely(world_to_grid, [1.2, 3.7], [1.0, 1.0])
    out["2d_input_3d_spacing"] = call_safely(world_to_grid, [1.2, 3.7], [1.0, 1.0, 1.0])
    out["halves"] = [
        call_safely(world_to_grid, [x, 0.0, 0.0], [1.0, 1.0, 1.0])
        for x in (0.5, 1.5, 2.5, -0.5, -1.5)
    ]
    out["near"] = [
        call_safely(world_to_grid, [x, 0.0, 0.0], [1.0, 1.0, 1.0])
        for x in (0.49, 0.51, 0.99, -0.49)
    ]
    out["spacing_0.5"] = call_safely(world_to_grid, [1.2, 3.7, 0.3], [0.5, 0.5, 0.5])
    out["zero_spacing_z"] = call_safely(world_to_grid, [1.0, 2.0, 0.05], [1.0, 1.0, 0.0])
with T.probe("grid_to_world") as out:
    out["3d"] = call_safely(grid_to_world, [1, 4, 0], [1.0, 1.0, 1.0])
    out["3d_offset"] = call_safely(grid_to_world, [1, 4, 0], [1.0, 1.0, 1.0], [0.5, 0.5, 0.05])
    out["2d_input"] = call_safely(grid_to_world, [1, 4], [1.0, 1.0])
    out["2d_input_offset"] = call_safely(grid_to_world, [1, 4], [0.5, 0.5], [1.0, 1.0])
    out["roundtrip"] = call_safely(
        lambda: world_to_grid(grid_to_world([3, 2, 1], [0.3, 0.3, 0.3]), [0.3, 0.3, 0.3])
    )
with T.probe("2d_wrappers") as out:
    out["world_to_grid_2d"] = call_safely(world_to_grid_2d, [1.2, 3.7], [1.0, 1.0])
    out["grid_to_world_2d"] = call_safely(grid_to_world_2d, [1, 4], [1.0, 1.0])
with T.probe("helpers") as out:
    out["body_to_world_2d"] = call_safely(body_to_world_velocity_2d, 1.0, 0.0, math.pi / 2)
    out["normalize_scalar"] = call_safely(normalize_vector_param, 2.0, "max_vel", 3)
    out["normalize_list"] = call_safely(normalize_vector_param, [1.0, 2.0, 3.0], "max_vel", 3)
    out["normalize_bad"] = call_safely(normalize_vector_param, [1.0, 2.0], "max_vel", 3)
    approach = calculate_offset_pose([5, 0, 0.1], [0, 0, 0.3], offset=1.5)
    out["offset_pose"] = [approach.position, approach.orientation]
    out["offset_pose_no_keep"] = call_safely(
        lambda: (
            calculate_offset_pose([5, 0, 0.1], [0, 0, 0.3], offset=1.5, keep_height=False).position
        )
    )
    out["offset_0"] = calculate_offset_pose([5, 0, 0.1], [0, 0, 0.3], offset=0.0).position
T.dump()
