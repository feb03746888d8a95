"""Route graphs: the YAML and LIF readers, quickest routes, who is on which edge, and the
FollowRouteAction that drives them."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleet_async import (
    Agent,
    FollowRouteAction,
    MultiRobotSimulationCore,
    Pose,
    RouteGraph,
    RouteNode,
    ShapeParams,
    load_route_graph,
)
from fleet_async.core.routes.follow import route_to_node
from tests.conftest import headless_params

DATA = Path(__file__).resolve().parents[2] / "data" / "traffic"
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def robot(sim, x=0.0, y=0.0, name="r"):
    return Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(x, y, 0.1), sim_core=sim, controller="omni", name=name
    )


def test_the_yaml_graph_has_nodes_edges_reverses_and_speeds():
    graph = load_route_graph(DATA / "loop.graph.yaml")
    assert sorted(graph.nodes) == ["A", "B", "C", "D"]
    assert graph.nodes["C"] == RouteNode("C", 4.0, 4.0, 1.5707963267948966, "hall")
    assert sorted(graph.edges) == ["AB", "AB~", "AC", "BC", "BC~", "CD", "CD~", "DA", "DA~"]
    assert (graph.edges["AB~"].start, graph.edges["AB~"].end) == ("B", "A")
    assert graph.edges["AC"].max_speed == 0.5
    assert graph.edges["AC"].length == pytest.approx(32**0.5)


def test_the_quickest_route_takes_the_fast_edges_not_the_short_slow_one():
    graph = load_route_graph(DATA / "loop.graph.yaml")
    # A-C direct: 5.66 m at 0.5 m/s = 11.3 s; A-B-C: 8 m at 2 m/s = 4 s
    assert [e.edge_id for e in graph.shortest_path("A", "C")] == ["AB", "BC"]
    assert [e.edge_id for e in graph.shortest_path("C", "A")] == ["BC~", "AB~"]
    assert graph.shortest_path("B", "B") == []
    with pytest.raises(KeyError, match="'Z'"):
        graph.shortest_path("A", "Z")


def test_an_unreachable_node_is_an_error():
    graph = RouteGraph()
    graph.add_node(RouteNode("a", 0.0, 0.0))
    graph.add_node(RouteNode("b", 1.0, 0.0))
    graph.add_edge("ab", "a", "b")
    with pytest.raises(ValueError, match="cannot be reached"):
        graph.shortest_path("b", "a")


def test_the_lif_reader_takes_positions_headings_and_the_vehicle_types_speed():
    graph = load_route_graph(DATA / "small.lif.json")
    assert graph.nodes["n1"] == RouteNode("n1", 0.0, 0.0, 0.0, "level0")
    assert graph.nodes["n2"].theta is None
    assert graph.edges["e12"].max_speed == 1.0
    assert graph.edges["e32"].max_speed is None
    tugger = load_route_graph(DATA / "small.lif.json", vehicle_type="tugger")
    assert tugger.edges["e12"].max_speed == 0.5
    assert [e.edge_id for e in graph.shortest_path("n1", "n3")] == ["e12", "e23"]


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"nodes": [{"id": "a", "x": 0, "y": 0, "z": 1}]}, "unknown key 'z'"),
        ({"nodes": [{"id": "a", "x": "far", "y": 0}]}, r"nodes\[0\].x"),
        (
            {
                "nodes": [{"id": "a", "x": 0, "y": 0}],
                "edges": [{"id": "e", "from": "a", "to": "b"}],
            },
            "'b'",
        ),
        ({"nodes": [{"id": "a", "x": 0, "y": 0}, {"id": "a", "x": 1, "y": 0}]}, "twice"),
        ({"edges": [], "colour": "red"}, "unknown key 'colour'"),
        ({"layouts": [{"layoutId": "x"}, {"layoutId": "y"}]}, "choose one with layout_id"),
    ],
)
def test_bad_graphs_are_refused_by_key(data, message):
    with pytest.raises(ValueError, match=message):
        load_route_graph(data)


def test_a_bad_file_is_named(tmp_path):
    path = tmp_path / "g.yaml"
    path.write_text("nodes:\n  - {id: a, x: 0, y: 0, speed: 3}\n")
    with pytest.raises(ValueError, match=r"g\.yaml.*speed"):
        load_route_graph(path)


def test_locate_and_occupancy_say_who_is_on_which_edge():
    graph = load_route_graph(DATA / "loop.graph.yaml")
    assert graph.locate([(2.0, 0.1), (4.1, 2.0), (2.0, 2.5)]) == ["AB", "BC", None]
    with MultiRobotSimulationCore(headless_params()) as sim:
        a, b = robot(sim, 1.0, 0.0, "a"), robot(sim, 0.0, 3.0, "b")
        assert graph.occupancy([a, b]) == {"AB": [a], "DA": [b]}


def test_route_to_node_starts_with_the_way_to_the_nearest_node():
    graph = load_route_graph(DATA / "loop.graph.yaml")
    with MultiRobotSimulationCore(headless_params()) as sim:
        r = robot(sim, 0.5, 0.5)
        action = route_to_node(r, graph, "C")
        assert [(leg.edge_id, leg.node_id) for leg in action.legs] == [
            (None, "A"),
            ("AB", "B"),
            ("BC", "C"),
        ]
        assert action.legs[-1].theta == pytest.approx(1.5707963267948966)


def test_a_queued_route_drives_each_edge_at_its_limit_and_lifts_the_cap():
    with MultiRobotSimulationCore(headless_params()) as sim:
        graph = sim.load_route_graph(DATA / "small.lif.json")
        assert sim.route_graph is graph
        r = robot(sim)
        action = route_to_node(r, graph, "n3")
        r.add_action(action)
        top, edges = {}, []
        for _ in range(120):
            sim.step_once()
            edge = action.current_edge
            if edge is not None:
                top[edge] = max(top.get(edge, 0.0), float((r.velocity[:2] ** 2).sum() ** 0.5))
                if not edges or edges[-1] != edge:
                    edges.append(edge)
        assert action.is_complete() and action.error_message is None
        assert edges == ["e12", "e23"]
        assert top["e12"] == pytest.approx(1.0)
        assert top["e23"] == pytest.approx(0.5)
        pose = r.get_pose()
        assert (pose.x, pose.y) == pytest.approx((3.0, 2.0))
        assert pose.yaw == pytest.approx(1.5707963267948966)
        assert r.controller_params.max_linear_vel == 2.0


def test_follow_route_needs_a_leg():
    with pytest.raises(ValueError, match="legs"):
        FollowRouteAction(legs=[])
