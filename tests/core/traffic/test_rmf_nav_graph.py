"""Open-RMF nav graphs as route graphs (``routes/rmf.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleet_async import MultiRobotSimulationCore
from fleet_async.core.routes import load_route_graph
from fleet_async.core.routes.rmf import route_graph_from_rmf
from tests.conftest import headless_params

SAMPLE = Path(__file__).resolve().parents[2] / "data" / "traffic" / "corridor.nav.yaml"


def test_the_sample_reads_as_nodes_and_directed_edges_with_limits():
    graph = load_route_graph(SAMPLE)
    assert sorted(graph.nodes) == ["L1#1", "charger_1", "l2_end", "l2_start", "lobby", "pantry"]
    lobby = graph.node("lobby")
    assert (lobby.x, lobby.y, lobby.map_id) == (4.0, 3.0, "L1")
    assert graph.node("l2_end").map_id == "L2"
    assert sorted(graph.edges) == [
        "L1#1>charger_1",
        "L1#1>lobby",
        "charger_1>L1#1",
        "l2_start>l2_end",
        "lobby>L1#1",
        "lobby>pantry",
        "pantry>lobby",  # the bidirectional lane's reverse
    ]
    assert graph.edges["lobby>pantry"].max_speed == 0.5
    assert graph.edges["pantry>lobby"].max_speed == 0.5
    assert graph.edges["charger_1>L1#1"].max_speed is None  # speed_limit 0: none
    assert graph.edges["l2_start>l2_end"].max_speed == 1.5
    path = graph.shortest_path("charger_1", "pantry")
    assert [e.edge_id for e in path] == ["charger_1>L1#1", "L1#1>lobby", "lobby>pantry"]
    with pytest.raises(ValueError, match="cannot be reached"):
        graph.shortest_path("l2_end", "l2_start")  # a one-way lane


def test_a_simulation_and_a_scenario_load_it_as_their_route_graph(tmp_path):
    with MultiRobotSimulationCore(headless_params()) as sim:
        graph = sim.load_route_graph(SAMPLE)
        assert sim.route_graph is graph
        assert len(graph.nodes) == 6
    config = {
        "simulation": {"gui": False, "monitor": False, "target_rtf": 0.0},
        "traffic": {"route_graph": str(SAMPLE)},
    }
    with MultiRobotSimulationCore.from_dict(config) as sim:
        assert sorted(sim.route_graph.nodes) == sorted(graph.nodes)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"levels": []}, "levels: expected a mapping of levels"),
        ({"levels": {"L1": {"vertices": [[0.0, "a", {}]]}}}, r"vertices\[0\].y: expected a number"),
        (
            {"levels": {"L1": {"vertices": [[0, 0, {"name": "a"}], [1, 0, {"name": "a"}]]}}},
            "the vertex name 'a' is used twice",
        ),
        (
            {"levels": {"L1": {"vertices": [[0, 0]], "lanes": [[0, 3, {}]]}}},
            r"lanes\[0\]: no vertex 3 \(the level has 1\)",
        ),
        (
            {
                "levels": {
                    "L1": {"vertices": [[0, 0], [1, 0]], "lanes": [[0, 1, {"speed_limit": "x"}]]}
                }
            },
            r"lanes\[0\].speed_limit: expected a number, got 'x'",
        ),
        ({"levels": {"L1": {"vertices": [[0, 0, 5]]}}}, "expected a mapping of parameters"),
    ],
)
def test_a_bad_nav_graph_is_refused_naming_the_file_and_the_entry(data, message):
    with pytest.raises(ValueError, match=message) as caught:
        route_graph_from_rmf(data, source="site.nav.yaml")
    assert str(caught.value).startswith("site.nav.yaml: Open-RMF nav graph: ")


def test_a_bad_file_names_itself(tmp_path):
    bad = tmp_path / "bad.nav.yaml"
    bad.write_text("levels:\n  L1:\n    vertices: [[0, 0, {name: a}]]\n    lanes: [[0, 1]]\n")
    with pytest.raises(ValueError, match=f"{bad}: Open-RMF nav graph: levels.L1.lanes"):
        load_route_graph(bad)
