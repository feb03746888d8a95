"""``await robot.go_to_node(node_id)`` on both backends, exact sim times."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleet_async import Agent, Pose, ShapeParams

DATA = Path(__file__).resolve().parents[1] / "data" / "traffic"
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


async def test_go_to_node_drives_the_quickest_route(fleet_sim):
    fleet_sim.load_route_graph(DATA / "loop.graph.yaml")
    r = Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(0.0, 0.0, 0.1), sim_core=fleet_sim, controller="omni"
    )
    action = await r.go_to_node("C")
    assert [leg.edge_id for leg in action.legs] == ["AB", "BC"]
    # two 4 m edges at 2 m/s and 5 m/s^2 (2.4 s each, stopping at B), then the quarter turn
    # to C's heading at 3 rad/s and 10 rad/s^2 (0.9 s)
    assert fleet_sim.step_count == 57
    assert (r.get_pose().x, r.get_pose().y) == pytest.approx((4.0, 4.0))


async def test_go_to_node_without_a_graph_says_so(fleet_sim):
    r = Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(0.0, 0.0, 0.1), sim_core=fleet_sim, controller="omni"
    )
    with pytest.raises(RuntimeError, match="no route graph"):
        await r.go_to_node("C")
