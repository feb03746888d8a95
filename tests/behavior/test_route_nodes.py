"""The GoToNode fleet node: a behaviour tree drives the route graph (both backends)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleet_async import Agent, Pose, ShapeParams
from fleet_async.behavior import BehaviorTreeError, BehaviorTreeFactory, NodeStatus

DATA = Path(__file__).resolve().parents[1] / "data" / "traffic"
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
<BehaviorTree ID="Main">
<Sequence><GoToNode node="B"/><GoToNode node="{home}"/></Sequence>
</BehaviorTree>
</root>"""


async def test_go_to_node_nodes_drive_there_and_back(fleet_sim):
    fleet_sim.load_route_graph(DATA / "loop.graph.yaml")
    robot = Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(0.0, 0.0, 0.1), sim_core=fleet_sim, controller="omni"
    )
    tree = BehaviorTreeFactory().create_tree_from_text(TREE, agent=robot, blackboard={"home": "A"})
    assert await tree.run() is NodeStatus.SUCCESS
    assert fleet_sim.step_count == 48  # 4 m at 2 m/s and 5 m/s^2 (2.4 s), twice
    assert (robot.get_pose().x, robot.get_pose().y) == pytest.approx((0.0, 0.0))


async def test_an_unknown_node_fails_the_tree_with_its_name(fleet_sim):
    fleet_sim.load_route_graph(DATA / "loop.graph.yaml")
    robot = Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(0.0, 0.0, 0.1), sim_core=fleet_sim, controller="omni"
    )
    tree = BehaviorTreeFactory().create_tree_from_text(TREE, agent=robot, blackboard={"home": "Z"})
    with pytest.raises((KeyError, BehaviorTreeError), match="Z"):
        await tree.run()
