"""VDA 5050 and safety fields: ``safetyState.fieldViolation`` and ``driving`` in the state,
the fields in the factsheet's ``agvGeometry.envelopes2d`` (both valid against the schemas)."""

from __future__ import annotations

import itertools
import json

import pytest

from fleet_async import Agent, AgentSpawnParams, Pose, ShapeParams, SimObject
from fleet_async.interfaces import FleetInterface, InMemoryTransport
from fleet_async.interfaces.vda5050 import encode
from fleet_async.interfaces.vda5050.config import Vda5050Config
from fleet_async.interfaces.vda5050.factsheet import describe
from fleet_async.interfaces.vda5050.schemas import validation_errors
from tests.interfaces.test_fleet_interface import route

BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.1])


def robot(sim, fields=True):
    params = AgentSpawnParams(
        visual_shape=BOX,
        collision_shape=BOX,
        initial_pose=Pose.from_xyz(0.0, 0.0, 0.1),
        name="r0",
        motion_mode="omnidirectional",
        safety_field=fields,
    )
    return Agent.from_params(params, sim)


def test_a_field_violation_is_reported_in_the_state_and_the_robot_is_not_driving(sim):
    agent = robot(sim)
    crate = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(3.0, 0.0, 0.1), sim_core=sim)
    fleet = FleetInterface(sim, state_period=30.0, visualization_period=0)
    link = InMemoryTransport(fleet)
    link.send("r0", route(points=((0, 0), (5, 0))))
    for _ in range(40):
        sim.step_once()
    assert sim.safety.is_stopped(agent)
    snap, why = link.states["r0"][-1]
    assert "field_violation" in why
    assert snap.field_violation and not snap.driving
    config = Vda5050Config()
    header = encode.Header(config, "r0", 0.0).make("state", snap.sim_time)
    state = encode.state(header, snap, "", config.version)
    assert state["safetyState"] == {"eStop": "NONE", "fieldViolation": True}
    assert state["driving"] is False
    assert validation_errors(config.version, "state", state) == []
    sim.remove_object(crate)
    for _ in range(60):
        sim.step_once()
    stop_ends = [s for s, why in link.states["r0"] if "field_violation" in why]
    assert not stop_ends[-1].field_violation
    assert agent.get_pose().position[0] == pytest.approx(5.0)


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_the_factsheet_lists_the_fields_as_envelopes(sim, version):
    agent = robot(sim, {"protective_margin": 0.2, "warning_margin": 1.0, "side_margin": 0.1})
    config = Vda5050Config(version=version)
    sheet = describe(agent, config)
    envelopes = {e["set"]: e["polygonPoints"] for e in sheet["agvGeometry"]["envelopes2d"]}
    assert sorted(envelopes) == [
        "protectiveField_maxSpeed",
        "protectiveField_standstill",
        "warningField_maxSpeed",
        "warningField_standstill",
    ]
    assert envelopes["protectiveField_standstill"] == [
        {"x": 0.3, "y": -0.3},
        {"x": 0.5, "y": -0.3},
        {"x": 0.5, "y": 0.3},
        {"x": 0.3, "y": 0.3},
    ]
    # 2 m/s, 1 m/s^2: 2 m to stop, + 0.2 m margin, + 1.0 m warning
    assert envelopes["warningField_maxSpeed"][1] == {"x": 3.5, "y": -0.3}
    body = {**encode.Header(config, "r0", 0.0).make("factsheet", 0.0), **sheet}
    assert validation_errors(version, "factsheet", body) == []


def test_a_robot_without_fields_has_no_envelopes(sim):
    agent = robot(sim, None)
    assert describe(agent, Vda5050Config())["agvGeometry"] == {}


def _order_naming_nodes(node_ids):
    header = encode.Header(Vda5050Config(), "r0", 0.0).make("order", 0.0)
    nodes = [
        {"nodeId": n, "sequenceId": 2 * i, "released": True, "actions": []}
        for i, n in enumerate(node_ids)
    ]
    edges = [
        {
            "edgeId": f"{a}-{b}",
            "sequenceId": 2 * i + 1,
            "released": True,
            "startNodeId": a,
            "endNodeId": b,
            "actions": [],
        }
        for i, (a, b) in enumerate(itertools.pairwise(node_ids))
    ]
    return {**header, "orderId": "o1", "orderUpdateId": 0, "nodes": nodes, "edges": edges}


def test_an_order_may_name_the_route_graphs_nodes_without_positions():
    from pathlib import Path

    from fleet_async import load_route_graph
    from fleet_async.interfaces import Order, Rejection
    from fleet_async.interfaces.vda5050.decode import decode

    graph = load_route_graph(Path(__file__).parents[1] / "data" / "traffic" / "small.lif.json")
    body = _order_naming_nodes(["n1", "n2", "n3"])
    assert validation_errors("2.1.0", "order", body) == []
    payload = json.dumps(body).encode()
    topic = "order"
    order = decode(topic, payload, Vda5050Config(route_graph=graph), "r0")
    assert isinstance(order, Order)
    assert [(n.node_id, n.x, n.y, n.theta, n.map_id) for n in order.nodes] == [
        ("n1", 0.0, 0.0, 0.0, "level0"),
        ("n2", 3.0, 0.0, None, "level0"),
        ("n3", 3.0, 2.0, pytest.approx(1.5707963267948966), "level0"),
    ]
    refused = decode(topic, payload, Vda5050Config(), "r0")
    assert isinstance(refused, Rejection) and "no nodePosition" in refused.description
    unknown = json.dumps(_order_naming_nodes(["n1", "zz"])).encode()
    refused = decode(topic, unknown, Vda5050Config(route_graph=graph), "r0")
    assert isinstance(refused, Rejection) and "route graph has no such node" in refused.description
