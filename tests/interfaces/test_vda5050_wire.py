"""What a served vehicle does with anything a master may put on the wire (plain paho, no SDK).

Each bad message must be answered in the state of the step that applied it, with the right
errorType and references; the vehicle's network thread must survive it, and a valid order
afterwards must still be driven to its end. Versions: a 2.1.0 vehicle takes 2.0.0 orders, and
a vehicle configured for 2.0.0 speaks 2.0.0 (the sniffer fixture validates every state,
visualization, connection and factsheet message against the vehicle's version).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import pytest

from fleet_async.interfaces.vda5050 import MAX_PAYLOAD_BYTES
from tests.interfaces.conftest import RawMaster, Served, Sniffer, step_of, vda_order, wait_until


def header(raw: RawMaster, served: Served, topic: str, version: str = "2.1.0") -> dict[str, Any]:
    """The next header the raw master sends the first robot on ``topic``."""
    serial = served.transport.serials[served.name]
    return raw.header(served.config.manufacturer, serial, topic, version)


def answer(served: Served, sniffer: Sniffer, step: int) -> dict[str, Any]:
    """The state the vehicle published at ``step``."""
    return sniffer.wait_state(lambda s: step_of(s["timestamp"]) == step, f"the state of {step}")


def errors(state: dict[str, Any]) -> list[str]:
    """The errorTypes of a state."""
    return [e["errorType"] for e in state["errors"]]


def references(error: dict[str, Any]) -> dict[str, str]:
    """An error's references as a dict."""
    return {r["referenceKey"]: r["referenceValue"] for r in error["errorReferences"]}


def drive_a_valid_order(
    served: Served, sniffer: Sniffer, raw: RawMaster, order_id: str = "o-after", x: float = 1.0
) -> dict[str, Any]:
    """Send a valid order from where the robot stands to ``x`` further; it must be accepted
    and driven to its end. Returns the state at the end."""
    link = served.transport._links[served.name]
    assert link.connected.is_set() and served.transport.loop.alive
    x0, y0 = served.xy()
    points = [("a0", x0, y0), ("a1", x0 + x, y0)]
    total = served.count() + 1
    raw.send(served.topic("order"), vda_order(header(raw, served, "order"), order_id, points))
    accepted = served.apply(total)
    state = answer(served, sniffer, accepted)
    assert state["orderId"] == order_id and errors(state) == [], state
    end = served.step_until(
        lambda: served.snapshot().last_node_id == "a1" and not served.agent.is_moving, "arrival"
    )
    px, py = served.xy()
    assert abs(px - (x0 + x)) < 1e-6 and abs(py - y0) < 1e-6
    final = sniffer.wait_state(lambda s: s["lastNodeId"] == "a1", "the state at the end")
    assert step_of(final["timestamp"]) == end and final["nodeStates"] == []
    return final


def valid_order_body(raw: RawMaster, served: Served, **changes: Any) -> bytes:
    """A valid order with header fields changed."""
    body = vda_order(header(raw, served, "order"), "o-v", [("v0", 0.0, 0.0), ("v1", 1.0, 0.0)])
    body.update(changes)
    return json.dumps(body).encode()


# ----- not a valid message: validationError ----------------------------------------------


def _nested(depth: int) -> bytes:
    return b"[" * depth + b"]" * depth


def _oversize() -> bytes:
    pad = "x" * (MAX_PAYLOAD_BYTES + 1)
    return json.dumps({"headerId": 7, "pad": pad}).encode()


INVALID: dict[str, tuple[str, Callable[[RawMaster, Served], bytes], str, bool]] = {
    # case: (topic, payload, a phrase of the description, whether headerId is referenced)
    "garbage": ("order", lambda r, s: b"\x00\x13garbage{{", "not JSON text", False),
    "not_utf8": ("order", lambda r, s: b'{"orderId": "\xff\xfe"}', "UnicodeDecodeError", False),
    "array": ("order", lambda r, s: b"[1, 2, 3]", "expected a JSON object, got list", False),
    "string": ("instantActions", lambda r, s: b'"cancel"', "got str", False),
    "null": ("instantActions", lambda r, s: b"null", "got NoneType", False),
    "nested_100k": ("order", lambda r, s: _nested(100_000), "RecursionError", False),
    "oversize": ("order", lambda r, s: _oversize(), f"exceeds {MAX_PAYLOAD_BYTES} bytes", False),
    "version_1": (
        "order",
        lambda r, s: valid_order_body(r, s, version="1.1.0"),
        "version '1.1.0' is not spoken here",
        True,
    ),
    "version_3": (
        "order",
        lambda r, s: valid_order_body(r, s, version="3.0.0"),
        "version '3.0.0' is not spoken here",
        True,
    ),
    "wrong_serial": (
        "order",
        lambda r, s: valid_order_body(r, s, serialNumber="somebody_else"),
        "serialNumber 'somebody_else' is not this vehicle's",
        True,
    ),
    "wrong_manufacturer": (
        "order",
        lambda r, s: valid_order_body(r, s, manufacturer="other_maker"),
        "manufacturer 'other_maker'",
        True,
    ),
    "schema": (
        "order",
        lambda r, s: valid_order_body(r, s, orderUpdateId=-1),
        "orderUpdateId",
        True,
    ),
    "instant_without_actions": (
        "instantActions",
        lambda r, s: json.dumps(header(r, s, "instantActions")).encode(),
        "actions",
        True,
    ),
}


@pytest.mark.parametrize("case", list(INVALID))
def test_an_invalid_message_is_answered_with_a_validation_error(
    case: str, serve: Callable[..., Served], sniffer: Sniffer, raw_master: RawMaster
) -> None:
    topic, make, phrase, has_header_id = INVALID[case]
    served = serve()
    served.step()  # step 0's state: no errors
    payload = make(raw_master, served)
    raw_master.send(served.topic(topic), payload)
    step = served.apply(1)

    state = answer(served, sniffer, step)
    assert errors(state) == ["validationError"]
    (error,) = state["errors"]
    assert error["errorLevel"] == "WARNING"
    assert phrase in error["errorDescription"], error["errorDescription"]
    expected = {"topic": topic}
    if has_header_id:
        expected["headerId"] = str(json.loads(payload)["headerId"])
    assert references(error) == expected
    assert (state["orderId"], state["nodeStates"], state["driving"]) == ("", [], False)
    assert served.transport.stats.rejected == 1

    final = drive_a_valid_order(served, sniffer, raw_master)
    assert errors(final) == []  # an accepted order clears the order errors


def test_many_bad_messages_in_a_row_never_stop_the_vehicle(
    serve: Callable[..., Served], sniffer: Sniffer, raw_master: RawMaster
) -> None:
    served = serve()
    for topic, make, _, _ in INVALID.values():
        raw_master.send(served.topic(topic), make(raw_master, served))
    step = served.apply(len(INVALID))
    state = answer(served, sniffer, step)
    assert errors(state) == ["validationError"] * len(INVALID)
    assert served.transport.stats.rejected == len(INVALID)
    drive_a_valid_order(served, sniffer, raw_master)


# ----- valid messages the vehicle cannot run: orderError, orderUpdateError ----------------


def _unknown_action(body: dict[str, Any]) -> None:
    body["nodes"][1]["actions"] = [
        {"actionType": "jump", "actionId": "jump-1", "blockingType": "HARD"}
    ]


def _no_position(body: dict[str, Any]) -> None:
    del body["nodes"][1]["nodePosition"]


def _trajectory(body: dict[str, Any]) -> None:
    body["edges"][0]["trajectory"] = {
        "degree": 1,
        "knotVector": [0.0, 0.0, 1.0, 1.0],
        "controlPoints": [{"x": 0.0, "y": 0.0}, {"x": 1.0, "y": 0.0}],
    }


ORDER_ERRORS = {
    "unknown_action_type": (
        _unknown_action,
        {"nodeId": "b1", "actionId": "jump-1", "actionType": "jump"},
    ),
    "node_without_position": (_no_position, {"nodeId": "b1", "field": "nodePosition"}),
    "edge_trajectory": (_trajectory, {"edgeId": "b0-b1", "field": "trajectory"}),
}


@pytest.mark.parametrize("case", list(ORDER_ERRORS))
def test_an_order_the_vehicle_cannot_run_is_an_order_error(
    case: str, serve: Callable[..., Served], sniffer: Sniffer, raw_master: RawMaster
) -> None:
    change, expected_refs = ORDER_ERRORS[case]
    served = serve()
    body = vda_order(
        header(raw_master, served, "order"), "o-bad", [("b0", 0.0, 0.0), ("b1", 1.0, 0.0)]
    )
    change(body)
    raw_master.send(served.topic("order"), body)
    step = served.apply(1)
    state = answer(served, sniffer, step)
    assert errors(state) == ["orderError"]
    refs = references(state["errors"][0])
    assert refs == {"orderId": "o-bad", "orderUpdateId": "0", **expected_refs}
    assert (state["orderId"], state["nodeStates"], state["actionStates"]) == ("", [], [])
    assert served.xy() == (0.0, 0.0)
    drive_a_valid_order(served, sniffer, raw_master)


def test_an_older_update_is_an_order_update_error_and_a_new_order_while_busy_an_order_error(
    serve: Callable[..., Served], sniffer: Sniffer, raw_master: RawMaster
) -> None:
    served = serve()
    route = [("c0", 0.0, 0.0), ("c1", 1.0, 0.0), ("c2", 2.0, 0.0), ("c3", 3.0, 0.0)]
    order = vda_order(header(raw_master, served, "order"), "o-1", route, update=2, released=2)
    raw_master.send(served.topic("order"), order)
    served.apply(1)
    served.step_until(lambda: served.snapshot().last_node_id == "c1", "arrival at c1")

    older = vda_order(header(raw_master, served, "order"), "o-1", route, update=1, released=3)
    raw_master.send(served.topic("order"), older)
    step = served.apply(2)
    state = answer(served, sniffer, step)
    assert errors(state) == ["orderUpdateError"]
    assert references(state["errors"][0]) == {"orderId": "o-1", "orderUpdateId": "1"}
    assert (state["orderId"], state["orderUpdateId"]) == ("o-1", 2)
    assert [n["nodeId"] for n in state["nodeStates"]] == ["c2", "c3"]

    other = vda_order(header(raw_master, served, "order"), "o-2", [("d0", 1.0, 0.0)])
    raw_master.send(served.topic("order"), other)
    step = served.apply(3)
    state = answer(served, sniffer, step)
    assert errors(state) == ["orderUpdateError", "orderError"]
    assert references(state["errors"][1]) == {"orderId": "o-2", "orderUpdateId": "0"}
    assert (state["orderId"], state["orderUpdateId"]) == ("o-1", 2)

    # The order goes on: update 3 releases the rest; it is driven to the end.
    update = vda_order(
        header(raw_master, served, "order"), "o-1", route[1:], update=3, first_sequence=2
    )
    raw_master.send(served.topic("order"), update)
    step = served.apply(4)
    state = answer(served, sniffer, step)
    assert errors(state) == [] and state["orderUpdateId"] == 3
    served.step_until(
        lambda: served.snapshot().last_node_id == "c3" and not served.agent.is_moving, "the end"
    )
    assert served.xy() == pytest.approx((3.0, 0.0), abs=1e-6)
    assert sniffer.wait_state(lambda s: s["lastNodeId"] == "c3", "the end")["nodeStates"] == []


# ----- versions ----------------------------------------------------------------------------


def test_a_2_0_order_is_run_by_a_2_1_vehicle(
    serve: Callable[..., Served], sniffer: Sniffer, raw_master: RawMaster
) -> None:
    served = serve()
    order = vda_order(
        header(raw_master, served, "order", "2.0.0"), "o-20", [("e0", 0.0, 0.0), ("e1", 2.0, 0.0)]
    )
    raw_master.send(served.topic("order"), order)
    step = served.apply(1)
    state = answer(served, sniffer, step)
    assert (state["orderId"], state["version"], errors(state)) == ("o-20", "2.1.0", [])
    served.step_until(
        lambda: served.snapshot().last_node_id == "e1" and not served.agent.is_moving, "the end"
    )
    assert served.xy() == pytest.approx((2.0, 0.0), abs=1e-6)


def test_a_vehicle_configured_for_2_0_speaks_2_0(
    serve: Callable[..., Served], sniffer: Sniffer, raw_master: RawMaster
) -> None:
    served = serve(version="2.0.0")
    assert sniffer.version == "2.0.0"  # the fixture validates against the 2.0.0 schemas
    garbage_then_order = [
        (served.topic("order"), b"{not json"),
        (
            served.topic("order"),
            vda_order(
                header(raw_master, served, "order", "2.0.0"),
                "o-20",
                [("f0", 0.0, 0.0), ("f1", 1.0, 0.0), ("f2", 2.0, 0.0)],
                released=2,
            ),
        ),
    ]
    for topic, message in garbage_then_order:
        raw_master.send(topic, message)
    step = served.apply(2)
    state = answer(served, sniffer, step)
    assert state["version"] == "2.0.0" and state["orderId"] == "o-20"
    assert isinstance(state["batteryState"]["batteryCharge"], int)
    served.step_until(lambda: served.snapshot().last_node_id == "f1", "arrival at f1")
    pause = {
        **header(raw_master, served, "instantActions", "2.0.0"),
        "actions": [
            {"actionType": "startPause", "actionId": "p-1", "blockingType": "HARD"},
            {"actionType": "jump", "actionId": "j-1", "blockingType": "NONE"},
        ],
    }
    raw_master.send(served.topic("instantActions"), pause)
    step = served.apply(3)
    state = answer(served, sniffer, step)
    assert state["paused"] is True
    actions = {a["actionId"]: a["actionStatus"] for a in state["actionStates"]}
    assert actions == {"p-1": "FINISHED", "j-1": "FAILED"}
    served.step(10)
    sniffer.sync()
    versions = {m.body["version"] for m in sniffer.of_vehicles()}
    assert versions == {"2.0.0"}
    assert {m.kind for m in sniffer.of_vehicles()} == {
        "state",
        "visualization",
        "connection",
        "factsheet",
    }


@pytest.mark.filterwarnings("ignore::pytest.PytestUnhandledThreadExceptionWarning")
@pytest.mark.parametrize("missing", ["manufacturer", "actions"])
def test_a_2_0_instant_actions_message_without_a_required_field_is_a_validation_error(
    missing: str, serve: Callable[..., Served], sniffer: Sniffer, raw_master: RawMaster
) -> None:
    served = serve()
    link = served.transport._links[served.name]
    body = {**header(raw_master, served, "instantActions", "2.0.0"), "actions": []}
    del body[missing]
    raw_master.send(served.topic("instantActions"), body)
    # Either the vehicle queues a command, or its network thread dies.
    loop = served.transport.loop
    wait_until(lambda: served.count() or not loop.alive, "the message handled (or fatal)")
    alive = loop.alive
    if not alive:  # no OFFLINE at the teardown: nothing would send it (5 s wasted)
        link.connected.clear()
    assert alive, "the vehicle's MQTT network thread died on a message"
    step = served.apply(1)
    assert errors(answer(served, sniffer, step)) == ["validationError"]
    drive_a_valid_order(served, sniffer, raw_master)
