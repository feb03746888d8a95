"""The trace carries what the viewer draws of traffic: the fields at a safety stop, the route
graph and the maps (docs/trace-format.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleet_async import MultiRobotSimulationCore, Pose
from fleet_async.core.routes import RouteGraph, RouteNode
from fleet_async.viewer import TraceReader
from tests.conftest import headless_params
from tests.core.traffic.test_safety_fields import robot, wall

DATA = Path(__file__).resolve().parents[2] / "data" / "traffic"


def events_of(path, kind):
    return [e for e in TraceReader(path).events if e["kind"] == kind]


def test_a_safety_stop_carries_its_fields_corners(tmp_path):
    path = tmp_path / "stop.fatrace"
    with MultiRobotSimulationCore(headless_params(enable_floor=True)) as sim:
        a = robot(sim, 0.0, name="a")
        w = wall(sim, 3.0)
        sim.start_trace(path)
        a.set_path([Pose.from_xyz(5.0, 0.0, 0.2)])
        for _ in range(40):
            sim.step_once()
        assert sim.safety.is_stopped(a)
        sim.stop_trace()
    (stop,) = events_of(path, "safety_stop_started")[:1]
    assert stop["object_id"] == a.object_id
    prot, warn = stop["data"]["protective"], stop["data"]["warning"]
    assert len(prot) == len(warn) == 4
    # Ahead of the robot (its front at x ~ 2.6..2.7), towards the wall at x = 2.7.
    xs = [x for x, _ in prot]
    assert max(xs) >= 2.7 - 0.3 - 1e-6 and min(xs) < max(xs)
    assert max(x for x, _ in warn) >= max(xs)  # the warning field reaches further
    assert stop["data"]["obstacles"] == [w.object_id]


def test_the_route_graph_is_in_the_trace_at_its_start_and_when_loaded(tmp_path):
    path = tmp_path / "graph.fatrace"
    with MultiRobotSimulationCore(headless_params()) as sim:
        sim.load_route_graph(DATA / "loop.graph.yaml")
        graph = sim.route_graph
        sim.start_trace(path)
        sim.step_once()
        small = RouteGraph()
        small.add_node(RouteNode("p", 0.0, 0.0))
        small.add_node(RouteNode("q", 1.0, 0.5))
        small.add_edge("pq", "p", "q")
        sim.set_route_graph(small)
        sim.step_once()
        sim.stop_trace()
    first, second = events_of(path, "route_graph")
    assert first["step"] == 0 and first["object_id"] is None
    assert {n[0] for n in first["data"]["nodes"]} == set(graph.nodes)
    assert len(first["data"]["edges"]) == len(graph.edges)
    edge = graph.edges[first["data"]["edges"][0][0]]
    assert first["data"]["edges"][0][1:] == [edge.start, edge.end]
    assert second["data"]["nodes"] == [["p", 0.0, 0.0], ["q", 1.0, 0.5]]
    assert [e[1:] for e in second["data"]["edges"]] == [["p", "q"]]


@pytest.mark.parametrize("before", [True, False])
def test_a_map_is_in_the_trace_as_its_rectangles(tmp_path, before):
    path = tmp_path / "map.fatrace"
    with MultiRobotSimulationCore(headless_params()) as sim:
        if not before:
            sim.start_trace(path)
        loaded = sim.load_map(DATA / "warehouse-small.map", resolution=0.5, tile=8.0)
        if before:
            sim.start_trace(path)
        sim.step_once()
        sim.stop_trace()
    (event,) = events_of(path, "map_loaded")
    data = event["data"]
    assert data["name"] == "warehouse-small"
    assert data["bodies"] == [b.object_id for b in loaded.bodies]
    assert len(data["rects"]) == len(loaded.lo)
    x0, y0, x1, y1 = data["rects"][0]
    assert [x0, y0] == pytest.approx(loaded.lo[0, :2])
    assert [x1, y1] == pytest.approx(loaded.hi[0, :2])


@pytest.mark.parametrize("how", ["add_grid_map", "add_map"])
def test_a_map_made_in_code_is_kept_and_traced_too(tmp_path, how):
    import numpy as np

    from fleet_async import OccupancyGrid
    from fleet_async.core.maps import add_grid_map

    path = tmp_path / "grid.fatrace"
    occupied = np.zeros((6, 8), dtype=bool)
    occupied[2, 1:7] = True
    grid = OccupancyGrid(occupied, resolution=0.5, origin=(0.0, 0.0))
    with MultiRobotSimulationCore(headless_params()) as sim:
        early = add_grid_map(sim, grid, name="early")  # before the trace: at its start
        sim.start_trace(path)
        sim.step_once()
        if how == "add_grid_map":
            late = add_grid_map(sim, grid, height=2.0, name="late")
        else:
            late = sim.add_map(grid, height=2.0, name="late")
        sim.step_once()
        sim.stop_trace()
        assert sim.maps == [early, late]
    first, second = events_of(path, "map_loaded")
    assert first["step"] == 0 and first["data"]["name"] == "early"
    assert second["step"] == 1 and second["data"]["name"] == "late"
    assert second["data"]["bodies"] == [b.object_id for b in late.bodies]
    assert second["data"]["rects"] == [[0.5, 1.0, 3.5, 1.5]]
