"""Served robots against a VDA 5050 master nobody here wrote: vda5050-sdk 0.2.0's MasterClient.

The master runs on its own thread and asyncio loop (as a fleet manager would, in real time);
the test thread steps the simulation by hand. Every test checks what the vehicle did twice:
from the states the master received and from the simulation itself, at exact steps (state
timestamps are EPOCH + sim time, so each state names the step it was taken at). The sniffer
fixture checks every message the vehicles published against the 2.1.0 schemas.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import socket
import threading
from collections.abc import Callable, Coroutine, Iterator
from itertools import pairwise
from typing import Any
from uuid import uuid4

import pytest

vda5050: Any = pytest.importorskip("vda5050", reason="needs vda5050-sdk (the test extra)")
pytest.importorskip("aiomqtt", reason="the vda5050-sdk master needs aiomqtt")

from vda5050 import (  # noqa: E402
    Action,
    ActionParameter,
    BlockingType,
    Edge,
    MasterClient,
    MasterConfig,
    Node,
    NodePosition,
    OrderBuilder,
)

from fleet_async import Pose, ShapeParams, SimObject  # noqa: E402
from fleet_async.interfaces.vda5050.schemas import validation_errors  # noqa: E402
from tests.interfaces.conftest import (  # noqa: E402
    TIMEOUT,
    RawMaster,
    Served,
    Sniffer,
    step_of,
    vda_order,
    wait_until,
)

BOTH_BROKERS = pytest.mark.parametrize("broker_url", ["mosquitto", "embedded"], indirect=True)
MAP = "map"
DEVIATION = 0.5  # m: the fleet interface's default allowedDeviationXY


class SdkMaster:
    """vda5050-sdk's ``MasterClient`` on a thread of its own, running ``asyncio.run``.

    ``call(coro)`` runs a coroutine of the client on that loop and returns its result; what the
    master receives (for the test's manufacturer only) is collected in ``states``,
    ``connections`` and ``factsheets``.

    Args:
        url: The broker.
        manufacturer: Which vehicles to collect messages of.
    """

    def __init__(self, url: str, manufacturer: str) -> None:
        self.url = url
        self.manufacturer = manufacturer
        self.states: list[Any] = []
        self.connections: list[Any] = []
        self.factsheets: list[Any] = []
        self.vehicle_errors: list[Any] = []
        self.client: Any = None
        self._lock = threading.Lock()
        self._ready = threading.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._failure: BaseException | None = None
        self._thread = threading.Thread(
            target=lambda: asyncio.run(self._main()), name="sdk-master", daemon=True
        )

    def _collect(self, into: list[Any]) -> Callable[[Any, Any], None]:
        def callback(message: Any, key: Any) -> None:
            if key.manufacturer == self.manufacturer:
                with self._lock:
                    into.append(message)

        return callback

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        config = MasterConfig(
            broker_url=self.url, client_id=f"sdk-master-{uuid4().hex}", progress_monitor=False
        )
        self.client = MasterClient(config)
        self.client.on_state(self._collect(self.states))
        self.client.on_connection(self._collect(self.connections))
        self.client.on_factsheet(self._collect(self.factsheets))
        self.client.on_vehicle_error(self._collect(self.vehicle_errors))
        try:
            await self.client.connect()
        except BaseException as exc:
            self._failure = exc
            self._ready.set()
            raise
        self._ready.set()
        try:
            await self._stop.wait()
        finally:
            # A master whose broker went away (a restart) has nothing left to disconnect.
            with contextlib.suppress(Exception):
                await asyncio.wait_for(self.client.disconnect(), TIMEOUT)

    def start(self) -> SdkMaster:
        """Connect (and subscribe); returns once the master listens."""
        self._thread.start()
        assert self._ready.wait(TIMEOUT), "the SDK master did not connect"
        if self._failure is not None:
            raise self._failure
        return self

    def call(self, coroutine: Coroutine[Any, Any, Any]) -> Any:
        """Run ``coroutine`` on the master's loop; its result."""
        assert self._loop is not None
        return asyncio.run_coroutine_threadsafe(coroutine, self._loop).result(TIMEOUT)

    def stop(self) -> None:
        """Disconnect and end the thread."""
        if self._loop is not None and self._stop is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(TIMEOUT)

    def received(self) -> list[Any]:
        """The states received so far."""
        with self._lock:
            return list(self.states)

    def wait_state(self, predicate: Callable[[Any], bool], what: str) -> Any:
        """The first state received that satisfies ``predicate``."""
        return wait_until(lambda: next((s for s in self.received() if predicate(s)), None), what)


@pytest.fixture
def master(broker_url: str, manufacturer: str) -> Iterator[SdkMaster]:
    """The SDK master on the test's broker, connected."""
    client = SdkMaster(broker_url, manufacturer).start()
    yield client
    client.stop()


def box(served: Served, name: str, x: float, y: float) -> Any:
    """A pickable 0.2 m box on the floor at (x, y)."""
    shape = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])
    return SimObject.from_mesh(
        shape, shape, Pose.from_xyz(x, y, 0.1), mass=1.0, sim_core=served.sim, name=name
    )


def line_order(
    served: Served, order_id: str, points: list[tuple[str, float]], released: int | None = None
) -> Any:
    """An SDK order along y = 0 through ``points`` (nodeId, x); the first ``released`` nodes
    (default all) are the base."""
    released = len(points) if released is None else released
    serial = served.transport.serials[served.name]
    builder = OrderBuilder(
        order_id=order_id, manufacturer=served.config.manufacturer, serial_number=serial
    )
    for i, (node_id, x) in enumerate(points):
        builder.add_node(node_id, x=x, y=0.0, map_id=MAP, released=i < released)
    for i, ((a, _), (b, _)) in enumerate(pairwise(points)):
        builder.add_edge(a, b, edge_id=f"{a}-{b}", released=i + 1 < released)
    return builder.build()


def dispatch(master: SdkMaster, served: Served, order: Any) -> None:
    """Send ``order`` through the SDK; it must pass the SDK's own acceptance checks."""
    result = master.call(master.client.dispatch(order, served.target()))
    assert result.accepted, result


def node_progress(states: list[Any]) -> list[tuple[str, int]]:
    """(lastNodeId, lastNodeSequenceId) in the order the states reported them, repeats merged."""
    out: list[tuple[str, int]] = []
    for s in states:
        here = (s.last_node_id, s.last_node_sequence_id)
        if not out or out[-1] != here:
            out.append(here)
    return out


def statuses(states: list[Any], action_id: str) -> list[str]:
    """An action's actionStatus over the states, repeats merged."""
    out: list[str] = []
    for s in states:
        for a in s.action_states:
            if a.action_id == action_id and (not out or out[-1] != a.action_status.value):
                out.append(a.action_status.value)
    return out


def node_ids(state: Any) -> list[tuple[str, int, bool]]:
    """A state's nodeStates as (nodeId, sequenceId, released)."""
    return [(n.node_id, n.sequence_id, n.released) for n in state.node_states]


def edge_ids(state: Any) -> list[tuple[str, int, bool]]:
    """A state's edgeStates as (edgeId, sequenceId, released)."""
    return [(e.edge_id, e.sequence_id, e.released) for e in state.edge_states]


def at(served: Served, x: float, y: float = 0.0) -> bool:
    """Whether the robot stands exactly (1e-6 m) at (x, y)."""
    px, py = served.xy()
    return abs(px - x) < 1e-6 and abs(py - y) < 1e-6


# ----- a. the base, the horizon and an order update ------------------------------------------


@BOTH_BROKERS
def test_order_is_driven_to_the_base_end_waits_and_an_update_drives_on(
    serve: Callable[..., Served], master: SdkMaster
) -> None:
    served = serve()
    agent = served.agent
    order = line_order(served, "o-base", [("n0", 0.0), ("n1", 1.0), ("n2", 2.0), ("n3", 3.0)], 3)
    dispatch(master, served, order)
    assert served.apply(1) == 0

    # The simulation's own record: the step at which each node was reached.
    reached: dict[str, int] = {"n0": 0}

    def arrived_at_base_end() -> bool:
        last = served.snapshot().last_node_id
        reached.setdefault(last, served.sim.step_count - 1)
        return last == "n2" and not agent.is_moving

    end_step = served.step_until(arrived_at_base_end, "arrival at n2")
    assert at(served, 2.0)
    master.wait_state(lambda s: s.last_node_id == "n2", "a state at n2")
    states = master.received()
    assert node_progress(states) == [("n0", 0), ("n1", 2), ("n2", 4)]
    for node_id, x in (("n1", 1.0), ("n2", 2.0)):
        first = next(s for s in states if s.last_node_id == node_id)
        assert step_of(first.timestamp) == reached[node_id]
        assert abs(first.agv_position.x - x) <= DEVIATION and first.agv_position.map_id == MAP

    # It waits at the base end: 5 s of sim time, not a millimetre, periodic states only.
    before = agent.get_pose()
    wait_start = served.sim.step_count
    for _ in range(50):
        served.sim.step_once()
        assert agent.get_pose().position.tolist() == before.position.tolist()
    periodic = [k for k in range(wait_start, served.sim.step_count) if k % 10 == 0]
    master.wait_state(lambda s: step_of(s.timestamp) == periodic[-1], "the last periodic state")
    waiting = [s for s in master.received() if wait_start <= step_of(s.timestamp)]
    assert [step_of(s.timestamp) for s in waiting] == periodic
    for s in waiting:
        assert (s.order_id, s.order_update_id, s.last_node_id) == ("o-base", 0, "n2")
        assert s.driving is False
        assert node_ids(s) == [("n3", 6, False)]
        assert edge_ids(s) == [("n2-n3", 5, False)]
    assert end_step < wait_start

    # An order update releases n3 and adds n4: the vehicle drives on to the end.
    result = master.call(
        master.client.extend_base(
            served.target(),
            extension_nodes=[
                Node(node_id="n3", sequence_id=0, released=True,
                     node_position=NodePosition(x=3.0, y=0.0, map_id=MAP)),
                Node(node_id="n4", sequence_id=0, released=True,
                     node_position=NodePosition(x=4.0, y=0.0, map_id=MAP)),
            ],
            extension_edges=[
                Edge(edge_id="n2-n3", sequence_id=0, released=True, start_node_id="n2",
                     end_node_id="n3"),
                Edge(edge_id="n3-n4", sequence_id=0, released=True, start_node_id="n3",
                     end_node_id="n4"),
            ],
        )
    )  # fmt: skip
    assert result.accepted, result
    update_step = served.apply(2)
    accepted = master.wait_state(lambda s: s.order_update_id == 1, "a state with orderUpdateId 1")
    assert step_of(accepted.timestamp) == update_step
    assert node_ids(accepted) == [("n3", 6, True), ("n4", 8, True)]
    assert edge_ids(accepted) == [("n2-n3", 5, True), ("n3-n4", 7, True)]
    assert accepted.errors == []

    def finished() -> bool:
        last = served.snapshot().last_node_id
        reached.setdefault(last, served.sim.step_count - 1)
        return last == "n4" and not agent.is_moving

    served.step_until(finished, "arrival at n4")
    assert at(served, 4.0)
    final = master.wait_state(lambda s: s.last_node_id == "n4", "a state at n4")
    assert step_of(final.timestamp) == reached["n4"]
    states = master.received()
    assert node_progress(states) == [("n0", 0), ("n1", 2), ("n2", 4), ("n3", 6), ("n4", 8)]
    assert step_of(next(s for s in states if s.last_node_id == "n3").timestamp) == reached["n3"]
    assert (final.order_id, final.order_update_id, final.last_node_sequence_id) == (
        "o-base",
        1,
        8,
    )
    assert node_ids(final) == [] and edge_ids(final) == []
    assert all(s.errors == [] for s in states)


# ----- b. node actions: pick and drop ----------------------------------------------------------


def load_action(action_type: str, action_id: str) -> Any:
    """A HARD pick or drop of load ``box_1``."""
    return Action(
        action_type=action_type,
        action_id=action_id,
        blocking_type=BlockingType.HARD,
        action_parameters=[ActionParameter(key="loadId", value="box_1")],
    )


@BOTH_BROKERS
def test_pick_at_one_node_and_drop_at_another(
    serve: Callable[..., Served], master: SdkMaster
) -> None:
    served = serve()
    load = box(served, "box_1", 2.0, 0.0)
    serial = served.transport.serials[served.name]
    order = (
        OrderBuilder(order_id="o-load", manufacturer=served.config.manufacturer,
                     serial_number=serial)
        .add_node("n0", x=0.0, y=0.0, map_id=MAP)
        .add_node("n1", x=2.0, y=0.0, map_id=MAP, actions=[load_action("pick", "pick-1")])
        .add_node("n2", x=4.0, y=0.0, map_id=MAP, actions=[load_action("drop", "drop-1")])
        .add_edge("n0", "n1", edge_id="e1")
        .add_edge("n1", "n2", edge_id="e2")
        .build()
    )  # fmt: skip
    dispatch(master, served, order)
    assert served.apply(1) == 0
    agent = served.agent

    # The simulation: the box rides along from n1 and stays at n2.
    carried_from = served.step_until(lambda: load.is_attached(), "the pick")
    assert at(served, 2.0)
    dropped_at = served.step_until(lambda: not load.is_attached(), "the drop")
    assert at(served, 4.0) and carried_from < dropped_at
    served.step_until(lambda: not served.fleet.vehicles[served.name].has_order, "order end")
    served.step(10)
    assert not agent.is_moving and at(served, 4.0)
    box_pose = load.get_pose()
    assert abs(box_pose.x - 4.0) < 1e-6 and abs(box_pose.y) < 1e-6

    # The master: WAITING -> RUNNING -> FINISHED for each; loads after the pick, none after
    # the drop; driving false while a HARD action runs.
    master.wait_state(
        lambda s: statuses([s], "drop-1") == ["FINISHED"], "a state with the drop finished"
    )
    states = master.received()
    assert statuses(states, "pick-1") == ["WAITING", "RUNNING", "FINISHED"]
    assert statuses(states, "drop-1") == ["WAITING", "RUNNING", "FINISHED"]
    for s in states:
        status = {a.action_id: a.action_status.value for a in s.action_states}
        assert {a.action_type for a in s.action_states} == {"pick", "drop"}
        if "RUNNING" in status.values():
            assert s.driving is False
        loads = [item.load_id for item in s.loads or []]
        if status["pick-1"] == "FINISHED" and status["drop-1"] != "FINISHED":
            assert loads == ["box_1"], s
        else:
            assert loads == [], s
    picking = next(s for s in states if statuses([s], "pick-1") == ["RUNNING"])
    assert picking.last_node_id == "n1" and abs(picking.agv_position.x - 2.0) < 1e-6
    dropping = next(s for s in states if statuses([s], "drop-1") == ["RUNNING"])
    assert dropping.last_node_id == "n2" and abs(dropping.agv_position.x - 4.0) < 1e-6
    # The box is attached (released) during a step; the next boundary reports it.
    picked = next(s for s in states if statuses([s], "pick-1") == ["FINISHED"])
    assert step_of(picked.timestamp) == carried_from + 1
    dropped = next(s for s in states if statuses([s], "drop-1") == ["FINISHED"])
    assert step_of(dropped.timestamp) == dropped_at + 1
    assert dropped.node_states == [] and dropped.errors == []


# ----- c. cancelOrder ----------------------------------------------------------------------------


def test_cancel_order_stops_the_vehicle_in_that_step(
    serve: Callable[..., Served], master: SdkMaster
) -> None:
    served = serve()
    agent = served.agent
    order = line_order(served, "o-cancel", [("n0", 0.0), ("n1", 2.0), ("n2", 4.0)])
    dispatch(master, served, order)
    served.apply(1)
    served.step_until(lambda: served.xy()[0] > 2.5, "driving past n1")
    assert agent.is_moving

    master.call(master.client.cancel_order(served.target(), action_id="cancel-1"))
    before = served.xy()
    cancel_step = served.apply(2)
    stopped = served.xy()
    assert stopped == before  # stopped at the boundary, before the step's motion
    for _ in range(20):
        served.sim.step_once()
        assert served.xy() == stopped
    assert not agent.is_moving

    cancelled = master.wait_state(
        lambda s: step_of(s.timestamp) == cancel_step, "the state of the cancel step"
    )
    assert cancelled.order_id == "o-cancel" and cancelled.last_node_id == "n1"
    assert node_ids(cancelled) == [] and edge_ids(cancelled) == []
    assert cancelled.driving is False
    assert (cancelled.agv_position.x, cancelled.agv_position.y) == stopped
    assert statuses([cancelled], "cancel-1") == ["FINISHED"]
    assert cancelled.errors == []

    # Nothing left to cancel: noOrderToCancel, naming the action; the cancel itself FAILED.
    master.call(master.client.cancel_order(served.target(), action_id="cancel-2"))
    second_step = served.apply(3)
    refused = master.wait_state(
        lambda s: step_of(s.timestamp) == second_step, "the state of the second cancel"
    )
    assert [e.error_type for e in refused.errors] == ["noOrderToCancel"]
    references = {(r.reference_key, r.reference_value) for r in refused.errors[0].error_references}
    assert ("actionId", "cancel-2") in references
    assert statuses([refused], "cancel-2") == ["FAILED"]
    assert refused.order_id == "o-cancel" and served.xy() == stopped
    wait_until(
        lambda: [e for e in master.vehicle_errors if e.error.error_type == "noOrderToCancel"],
        "the SDK's vehicle-error event",
    )


# ----- d. startPause / stopPause -------------------------------------------------------------


def test_pause_freezes_the_vehicle_and_resume_finishes_the_order(
    serve: Callable[..., Served], master: SdkMaster
) -> None:
    served = serve()
    agent = served.agent
    dispatch(master, served, line_order(served, "o-pause", [("n0", 0.0), ("n1", 4.0)]))
    served.apply(1)
    served.step_until(lambda: served.xy()[0] > 1.0, "driving")

    master.call(master.client.pause(served.target(), action_id="pause-1"))
    frozen = served.xy()
    pause_step = served.apply(2)
    assert served.xy() == frozen
    for _ in range(30):
        served.sim.step_once()
        assert served.xy() == frozen
    assert not agent.is_moving
    paused = master.wait_state(lambda s: step_of(s.timestamp) == pause_step, "the pause state")
    assert paused.paused is True and paused.driving is False
    assert statuses([paused], "pause-1") == ["FINISHED"]
    assert node_ids(paused) == [("n1", 2, True)]
    periodic = (served.sim.step_count - 1) // 10 * 10
    assert periodic > pause_step
    last = master.wait_state(lambda s: step_of(s.timestamp) == periodic, "a periodic state")
    assert last.paused is True and (last.agv_position.x, last.agv_position.y) == frozen

    master.call(master.client.resume(served.target(), action_id="resume-1"))
    resume_step = served.apply(3)
    resumed = master.wait_state(lambda s: step_of(s.timestamp) == resume_step, "the resume")
    assert resumed.paused is False and statuses([resumed], "resume-1") == ["FINISHED"]
    served.step()
    assert served.xy() != frozen  # it drives on
    end = served.step_until(
        lambda: served.snapshot().last_node_id == "n1" and not agent.is_moving, "arrival"
    )
    assert at(served, 4.0)
    final = master.wait_state(lambda s: s.last_node_id == "n1", "the state at n1")
    assert step_of(final.timestamp) == end and final.node_states == []
    assert final.paused is False and final.errors == []


# ----- e. a malformed order --------------------------------------------------------------------


def test_a_malformed_order_is_answered_with_a_validation_error_and_disturbs_nothing(
    serve: Callable[..., Served], master: SdkMaster, raw_master: RawMaster
) -> None:
    served = serve()
    agent = served.agent
    dispatch(master, served, line_order(served, "o-main", [("n0", 0.0), ("n1", 4.0)]))
    served.apply(1)
    served.step_until(lambda: served.xy()[0] > 1.0, "driving")

    # The SDK's builder refuses an order without nodes: a plain client sends it.
    serial = served.transport.serials[served.name]
    bad = vda_order(
        raw_master.header(served.config.manufacturer, serial, "order", "2.1.0"),
        "o-bad",
        [("x0", 0.0, 0.0), ("x1", 1.0, 0.0)],
    )
    del bad["nodes"]
    raw_master.send(served.topic("order"), bad)
    before = served.snapshot()
    reject_step = served.apply(2)
    after = served.snapshot()
    assert after.x > before.x  # the step drove on
    assert (after.order_id, after.order_update, after.nodes, after.edges) == (
        before.order_id,
        before.order_update,
        before.nodes,
        before.edges,
    )

    answer = master.wait_state(
        lambda s: step_of(s.timestamp) == reject_step, "the state answering the bad order"
    )
    assert [e.error_type for e in answer.errors] == ["validationError"]
    error = answer.errors[0]
    assert "nodes" in error.error_description
    references = {(r.reference_key, r.reference_value) for r in error.error_references}
    assert references == {("headerId", str(bad["headerId"])), ("topic", "order")}
    assert answer.order_id == "o-main" and answer.driving is True
    assert node_ids(answer) == [("n1", 2, True)]

    end = served.step_until(
        lambda: served.snapshot().last_node_id == "n1" and not agent.is_moving, "arrival"
    )
    assert at(served, 4.0)
    final = master.wait_state(lambda s: s.last_node_id == "n1", "the state at n1")
    assert step_of(final.timestamp) == end
    assert final.order_id == "o-main" and final.node_states == []
    assert served.transport.stats.rejected == 1 and served.transport.stats.received == 2


# ----- f. stateRequest, factsheetRequest ---------------------------------------------------------


def test_state_request_and_factsheet_request_are_answered(
    serve: Callable[..., Served], master: SdkMaster, sniffer: Sniffer
) -> None:
    served = serve(state_period=30.0)  # periodic states only at steps 0, 300 ...
    served.step(3)
    master.call(master.client.request_state(served.target()))
    request_step = served.apply(1)
    answer = master.wait_state(
        lambda s: step_of(s.timestamp) == request_step, "the state answering stateRequest"
    )
    assert statuses([answer], "state-request") == ["FINISHED"]
    assert [step_of(s.timestamp) for s in master.received()] == [0, request_step]

    wait_until(lambda: master.factsheets, "the factsheet published on connection")
    master.call(master.client.request_factsheet(served.target()))
    factsheet_step = served.apply(2)
    message = sniffer.wait_for(
        "factsheet", lambda body: body["headerId"] == 1, "the requested factsheet"
    )
    body = message.body
    assert validation_errors("2.1.0", "factsheet", body) == []
    assert (body["manufacturer"], body["serialNumber"], body["version"]) == (
        served.config.manufacturer,
        served.transport.serials[served.name],
        "2.1.0",
    )
    assert step_of(body["timestamp"]) == factsheet_step
    actions = {a["actionType"] for a in body["protocolFeatures"]["agvActions"]}
    assert {"pick", "drop", "cancelOrder", "startPause", "stopPause"} <= actions
    wait_until(lambda: len(master.factsheets) >= 2, "the requested factsheet at the master")
    assert master.factsheets[-1].type_specification.agv_kinematic == "DIFF"
    assert statuses(master.received(), "factsheet-request") == ["FINISHED"]

    # Retained: a master that subscribes later gets this factsheet at once.
    late = Sniffer(served.transport.address.url, served.config.manufacturer)
    try:
        retained = wait_until(
            lambda: late.of("factsheet"), "the retained factsheet for a late subscriber"
        )[0]
    finally:
        late.close()
    assert retained.retain is True and json.loads(retained.payload) == body


# ----- g. connection ---------------------------------------------------------------------------


def connection_states(messages: list[Any]) -> list[tuple[str, int]]:
    """(connectionState, headerId) of connection messages."""
    return [(m.body["connectionState"], m.body["headerId"]) for m in messages]


def late_messages(served: Served, kind: str) -> list[Any]:
    """What a subscriber that comes now gets at once on ``kind`` (retained), at QoS 2."""
    late = Sniffer(served.transport.address.url, served.config.manufacturer, qos=2)
    try:
        return list(wait_until(lambda: late.of(kind), f"a retained {kind} message"))
    finally:
        late.close()


def test_online_connection_broken_and_offline(
    serve: Callable[..., Served], master: SdkMaster, sniffer: Sniffer
) -> None:
    served = serve()
    transport = served.transport
    link = transport._links[served.name]

    # ONLINE on start: retained, QoS 1 (a QoS 2 subscriber gets it at the publish's QoS).
    online = sniffer.wait_for("connection", lambda b: b["connectionState"] == "ONLINE", "ONLINE")
    assert online.body["headerId"] == 1  # 0 is the last will's
    (retained,) = late_messages(served, "connection")
    assert (retained.retain, retained.qos, retained.body) == (True, 1, online.body)
    (factsheet,) = late_messages(served, "factsheet")
    assert (factsheet.retain, factsheet.qos) == (True, 0)
    wait_until(lambda: master.connections, "ONLINE at the master")
    served.step()

    # The vehicle's link dies without DISCONNECT: the broker delivers its last will.
    link.client.socket().shutdown(socket.SHUT_RDWR)
    broken = sniffer.wait_for(
        "connection", lambda b: b["connectionState"] == "CONNECTIONBROKEN", "the last will"
    )
    assert broken.body["headerId"] == 0 and step_of(broken.body["timestamp"]) == 0
    wait_until(
        lambda: [c for c in master.connections if c.connection_state == "CONNECTIONBROKEN"],
        "CONNECTIONBROKEN at the master",
    )
    # paho reconnects by itself: ONLINE again (and the factsheet), retained.
    wait_until(lambda: transport.stats.connects == 2, "the vehicle's reconnection")
    again = sniffer.wait_for(
        "connection", lambda b: b["headerId"] == 2, "ONLINE after the reconnection"
    )
    assert again.body["connectionState"] == "ONLINE"
    sniffer.wait_for("factsheet", lambda b: b["headerId"] == 1, "the factsheet again")
    wait_until(
        lambda: (
            [c.connection_state for c in master.connections][-1:] == ["ONLINE"]
            and len(master.connections) >= 3
        ),
        "ONLINE again at the master",
    )
    # It subscribed again: a stateRequest is answered.
    master.call(master.client.request_state(served.target()))
    request_step = served.apply(1)
    answer = master.wait_state(
        lambda s: step_of(s.timestamp) == request_step, "a state after the reconnection"
    )
    assert statuses([answer], "state-request") == ["FINISHED"]

    # A clean stop: OFFLINE (retained), then DISCONNECT, so no last will.
    transport.stop()
    offline = sniffer.wait_for("connection", lambda b: b["connectionState"] == "OFFLINE", "OFFLINE")
    assert offline.body["headerId"] == 3
    (retained,) = late_messages(served, "connection")
    assert (retained.retain, retained.body) == (True, offline.body)
    sniffer.sync()
    assert connection_states(sniffer.of("connection")) == [
        ("ONLINE", 1),
        ("CONNECTIONBROKEN", 0),
        ("ONLINE", 2),
        ("OFFLINE", 3),
    ]
    wait_until(
        lambda: [c.connection_state for c in master.connections][-1:] == ["OFFLINE"],
        "OFFLINE at the master",
    )


@pytest.mark.parametrize("broker_url", ["embedded"], indirect=True)
def test_after_a_broker_restart_the_vehicle_reconnects_and_finishes_its_order(
    serve: Callable[..., Served],
    master: SdkMaster,
    sniffer: Sniffer,
    embedded_broker: Any,
    broker_url: str,
    manufacturer: str,
) -> None:
    served = serve()
    agent = served.agent
    transport = served.transport
    dispatch(master, served, line_order(served, "o-restart", [("n0", 0.0), ("n1", 6.0)]))
    served.apply(1)
    served.step_until(lambda: served.xy()[0] > 1.0, "driving")

    embedded_broker.restart()
    served.step(5)  # the vehicle drives on while it has no broker
    wait_until(lambda: transport.stats.connects == 2, "the vehicle's reconnection")
    # It announces itself again: ONLINE and the factsheet, retained on the new broker.
    sniffer.wait_for("connection", lambda b: b["headerId"] == 2, "ONLINE after the restart")
    sniffer.wait_for("factsheet", lambda b: b["headerId"] == 1, "the factsheet again")

    # The SDK master does not reconnect by itself: a fresh one, as after a master restart.
    fresh = SdkMaster(broker_url, manufacturer).start()
    try:
        wait_until(
            lambda: [c for c in fresh.connections if c.connection_state == "ONLINE"],
            "ONLINE at the fresh master",
        )
        wait_until(lambda: fresh.factsheets, "the factsheet at the fresh master")
        end = served.step_until(
            lambda: served.snapshot().last_node_id == "n1" and not agent.is_moving, "arrival"
        )
        assert at(served, 6.0)
        final = fresh.wait_state(lambda s: s.last_node_id == "n1", "the state at n1")
        assert step_of(final.timestamp) == end
        assert (final.order_id, final.node_states, final.errors) == ("o-restart", [], [])
    finally:
        fresh.stop()
