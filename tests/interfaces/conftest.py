"""Fixtures of the VDA 5050 integration tests: brokers, served robots, a sniffer, masters.

The simulation is stepped by the test itself (``sim.step_once()``), so everything the vehicle
does happens at an exact step; only the network side waits on the wall clock, with a generous
deadline (:data:`TIMEOUT`) that a passing test never reaches.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from datetime import datetime, timezone
from itertools import pairwise
from typing import Any
from uuid import uuid4

import pytest

from fleet_async import Agent, AgentSpawnParams, MultiRobotSimulationCore, Pose
from fleet_async.interfaces import FleetInterface, VehicleSnapshot
from fleet_async.interfaces import broker as broker_module
from fleet_async.interfaces.vda5050 import BrokerAddress, MqttTransport, Vda5050Config
from fleet_async.interfaces.vda5050.schemas import validation_errors
from tests.conftest import headless_params

TIMEOUT = 15.0
"""s: wall-clock deadline for anything the network does (a loaded CI machine)."""
MOSQUITTO_URL = "mqtt://127.0.0.1:1883"
EPOCH = 1_767_225_600.0
"""2026-01-01T00:00:00Z: the wall-clock time of sim time 0 in every timestamp."""
DT = 0.1
"""s: the simulations' timestep."""
VEHICLE_TOPICS = frozenset({"state", "visualization", "connection", "factsheet"})
"""What vehicles publish (each payload is checked against the schemas)."""


def wait_until(predicate: Callable[[], Any], what: str, timeout: float = TIMEOUT) -> Any:
    """Poll ``predicate`` until it returns something truthy (returned), or fail naming ``what``."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            pytest.fail(f"no {what} within {timeout:g} s")
        time.sleep(0.002)


def step_of(timestamp: str) -> int:
    """The step a message's ``timestamp`` stands for (timestamps are EPOCH + sim time, in ms)."""
    moment = datetime.fromisoformat(timestamp.replace("Z", "+00:00")).timestamp()
    step = round((moment - EPOCH) / DT)
    assert abs(moment - EPOCH - step * DT) < 1.5e-3, timestamp
    return step


def now_iso() -> str:
    """The current time as a VDA 5050 timestamp."""
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def _address(url: str) -> BrokerAddress:
    return BrokerAddress.parse(url)


def _paho() -> Any:
    """paho-mqtt's client module (the test is skipped without the vda5050 extra)."""
    pytest.importorskip("jsonschema", reason="VDA 5050 validation needs jsonschema")
    return pytest.importorskip("paho.mqtt.client", reason="the MQTT tests need paho-mqtt")


# ----- brokers -----------------------------------------------------------------------------


@pytest.fixture(scope="session")
def mosquitto() -> str:
    """The shared Mosquitto on 127.0.0.1:1883 (CI starts one; skipped elsewhere without it)."""
    if not broker_module._probe("127.0.0.1", 1883):
        message = "no MQTT broker answers on 127.0.0.1:1883 (start mosquitto)"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    return MOSQUITTO_URL


@pytest.fixture(scope="module")
def embedded_broker() -> Iterator[Any]:
    """One embedded (amqtt) broker for the module's tests."""
    pytest.importorskip("amqtt", reason="the embedded MQTT broker needs amqtt")
    with broker_module.EmbeddedBroker() as running:
        yield running


@pytest.fixture
def broker_url(request: pytest.FixtureRequest) -> str:
    """The broker of a test: Mosquitto, or the embedded one when parametrized ``"embedded"``."""
    kind = getattr(request, "param", "mosquitto")
    if kind == "embedded":
        url: str = request.getfixturevalue("embedded_broker").url
        return url
    assert kind == "mosquitto", kind
    mosquitto_url: str = request.getfixturevalue("mosquitto")
    return mosquitto_url


@pytest.fixture
def manufacturer() -> str:
    """A manufacturer no other run uses: retained messages of other runs never leak in."""
    return f"fa_test_{uuid4().hex[:8]}"


# ----- a sniffer: every message of the test's manufacturer ------------------------------------


@dataclass(frozen=True)
class Message:
    """One message the sniffer received."""

    topic: str
    payload: bytes
    qos: int
    retain: bool

    @property
    def kind(self) -> str:
        """The topic's last level (``state``, ``connection`` ...)."""
        return self.topic.rsplit("/", 1)[-1]

    @property
    def serial(self) -> str:
        """The topic's serialNumber level."""
        return self.topic.split("/")[3]

    @property
    def body(self) -> Any:
        """The payload as JSON."""
        return json.loads(self.payload)


class Sniffer:
    """A plain paho client subscribed (QoS 1) to ``uagv/v2/<manufacturer>/#``.

    Args:
        url: The broker.
        manufacturer: The topic level to listen to.
        qos: The subscription's QoS (2: Mosquitto delivers at the QoS of the publish).
    """

    def __init__(self, url: str, manufacturer: str, qos: int = 1) -> None:
        self.qos = qos
        self.manufacturer = manufacturer
        self.prefix = f"uagv/v2/{manufacturer}"
        self.version = "2.1.0"  # the served vehicles' version (set by the serve fixture)
        self.messages: list[Message] = []
        self._lock = threading.Lock()
        self._subscribed = threading.Event()
        address = _address(url)
        mqtt = _paho()
        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=f"sniffer-{uuid4().hex}")
        client.reconnect_delay_set(min_delay=1, max_delay=1)
        client.on_connect = self._on_connect
        client.on_subscribe = lambda *args: self._subscribed.set()
        client.on_message = self._on_message
        client.connect(address.host, address.port, keepalive=15)
        client.loop_start()
        self.client = client
        wait_until(self._subscribed.is_set, f"SUBACK for the sniffer on {url}")

    def _on_connect(self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any) -> None:
        client.subscribe(f"{self.prefix}/#", qos=self.qos)  # again after a reconnection (amqtt)

    def _on_message(self, client: Any, userdata: Any, message: Any) -> None:
        with self._lock:
            self.messages.append(
                Message(message.topic, bytes(message.payload), message.qos, message.retain)
            )

    def of(self, kind: str, serial: str | None = None) -> list[Message]:
        """The messages on topic ``kind`` (of vehicle ``serial``), in arrival order."""
        with self._lock:
            return [
                m
                for m in self.messages
                if m.kind == kind and (serial is None or m.serial == serial) and m.payload
            ]

    def wait_for(
        self, kind: str, predicate: Callable[[Any], bool], what: str, serial: str | None = None
    ) -> Message:
        """The first message on ``kind`` whose JSON body satisfies ``predicate``."""

        def find() -> Message | None:
            return next((m for m in self.of(kind, serial) if predicate(m.body)), None)

        found: Message = wait_until(find, what)
        return found

    def states(self, serial: str | None = None) -> list[dict[str, Any]]:
        """Every state body received."""
        return [m.body for m in self.of("state", serial)]

    def wait_state(self, predicate: Callable[[dict[str, Any]], bool], what: str) -> dict[str, Any]:
        """The first state body that satisfies ``predicate``."""
        body: dict[str, Any] = self.wait_for("state", predicate, what).body
        return body

    def sync(self) -> None:
        """Wait until everything published before now reached the sniffer (a marker's round
        trip: the broker forwards in the order it handled the messages)."""
        marker = f"{self.prefix}/_sniffer/sync"
        token = uuid4().hex.encode()
        self.client.publish(marker, token, qos=1).wait_for_publish(TIMEOUT)

        def arrived() -> bool:
            with self._lock:
                return any(m.topic == marker and m.payload == token for m in self.messages)

        wait_until(arrived, "the sniffer's own marker")

    def schema_problems(self) -> list[str]:
        """Every vehicle message that does not validate against the vehicles' version."""
        problems = []
        for message in self.of_vehicles():
            try:
                body = message.body
            except ValueError as exc:
                problems.append(f"{message.topic}: not JSON ({exc})")
                continue
            for problem in validation_errors(self.version, message.kind, body):
                problems.append(f"{message.topic} headerId {body.get('headerId')}: {problem}")
        return problems

    def of_vehicles(self) -> list[Message]:
        """Every non-empty message vehicles published."""
        with self._lock:
            return [m for m in self.messages if m.kind in VEHICLE_TOPICS and m.payload]

    def clean_retained(self) -> None:
        """Clear the retained topics the vehicles used (an empty retained message)."""
        retained = ("connection", "factsheet")
        for topic in sorted({m.topic for m in self.of_vehicles() if m.kind in retained}):
            self.client.publish(topic, b"", qos=1, retain=True).wait_for_publish(TIMEOUT)

    def close(self) -> None:
        """Disconnect."""
        self.client.disconnect()
        self.client.loop_stop()


@pytest.fixture
def sniffer(broker_url: str, manufacturer: str) -> Iterator[Sniffer]:
    """Listens to the test's manufacturer; at the end checks every state, visualization,
    connection and factsheet message the vehicles published against the schemas of their
    version, and clears the retained topics."""
    listener = Sniffer(broker_url, manufacturer)
    yield listener
    try:
        listener.sync()
        problems = listener.schema_problems()
        seen = {m.kind for m in listener.of_vehicles()}
        listener.clean_retained()
    finally:
        listener.close()
    assert problems == []
    assert "connection" in seen, "the sniffer heard no vehicle at all"


# ----- served robots -------------------------------------------------------------------------


@dataclass
class Served:
    """A headless simulation whose robots are VDA 5050 vehicles on a broker.

    The test steps the simulation; commands arriving from the network are counted in
    ``commands`` (after the fleet interface queued them), so a test can wait until the vehicle
    has one and then step: the command is applied at that step's boundary.
    """

    sim: MultiRobotSimulationCore
    agents: dict[str, Any]
    fleet: FleetInterface
    transport: MqttTransport
    config: Vda5050Config
    commands: list[tuple[str, Any]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    @property
    def agent(self) -> Any:
        """The first robot."""
        return next(iter(self.agents.values()))

    @property
    def name(self) -> str:
        """The first robot's name (its serialNumber too)."""
        return next(iter(self.agents))

    def target(self, name: str | None = None) -> str:
        """``manufacturer/serialNumber`` of a robot (the SDK master's target)."""
        serial = self.transport.serials[name or self.name]
        return f"{self.config.manufacturer}/{serial}"

    def topic(self, kind: str, name: str | None = None) -> str:
        """The full topic ``kind`` of a robot."""
        return self.config.topic(self.transport.serials[name or self.name], kind)

    def count(self) -> int:
        """Commands the vehicles received so far."""
        with self.lock:
            return len(self.commands)

    def wait_commands(self, total: int) -> list[tuple[str, Any]]:
        """Wait until ``total`` commands have arrived in all; return them."""
        wait_until(lambda: self.count() >= total, f"command #{total} at the vehicle")
        with self.lock:
            return list(self.commands)

    def apply(self, total: int) -> int:
        """Wait for command #``total``, then step once: returns the step that applied it."""
        self.wait_commands(total)
        assert self.count() == total, "more commands arrived than the test sent"
        step = self.sim.step_count
        self.sim.step_once()
        return step

    def step(self, count: int = 1) -> None:
        """Step ``count`` times."""
        for _ in range(count):
            self.sim.step_once()

    def step_until(self, predicate: Callable[[], bool], what: str, limit: int = 1000) -> int:
        """Step until ``predicate`` holds after a step; returns that step's number."""
        for _ in range(limit):
            self.sim.step_once()
            if predicate():
                return int(self.sim.step_count - 1)
        pytest.fail(f"{what} did not happen within {limit} steps")

    def snapshot(self, name: str | None = None) -> VehicleSnapshot:
        """A robot's vehicle state now."""
        return self.fleet.snapshot(name or self.name)

    def xy(self, name: str | None = None) -> tuple[float, float]:
        """A robot's position."""
        pose = self.agents[name or self.name].get_pose()
        return float(pose.x), float(pose.y)


@pytest.fixture
def serve(broker_url: str, manufacturer: str, sniffer: Sniffer) -> Iterator[Callable[..., Served]]:
    """Make served simulations: ``serve(robots={"robot_0": (0, 0)}, version=..., ...)``."""
    made: list[Served] = []

    def make(
        robots: dict[str, tuple[float, float]] | None = None,
        *,
        version: str = "2.1.0",
        state_period: float = 1.0,
        visualization_period: float = 0.5,
        url: str | None = None,
    ) -> Served:
        sim = MultiRobotSimulationCore(headless_params(timestep=DT))
        agents = {}
        for name, (x, y) in (robots or {"robot_0": (0.0, 0.0)}).items():
            spawn = AgentSpawnParams(
                urdf_path="robots/mobile_robot.urdf",
                initial_pose=Pose.from_xyz(x, y, 0.05),
                name=name,
            )
            agents[name] = Agent.from_params(spawn, sim)
        fleet = FleetInterface(
            sim, state_period=state_period, visualization_period=visualization_period
        )
        config = Vda5050Config(
            version=version,
            manufacturer=manufacturer,
            state_period=state_period,
            visualization_period=visualization_period,
            epoch=EPOCH,
        )
        sniffer.version = version
        transport = MqttTransport(fleet, config, url or broker_url)
        served = Served(sim, agents, fleet, transport, config)
        submit = fleet.submit

        def counting_submit(vehicle: str, command: Any) -> None:
            submit(vehicle, command)
            with served.lock:
                served.commands.append((vehicle, command))

        fleet.submit = counting_submit  # type: ignore[method-assign]
        made.append(served)
        transport.start(timeout=TIMEOUT)
        # start() returns once the links are connected, before the broker has acknowledged
        # their subscriptions; a vehicle's ONLINE (published after its SUBSCRIBE on the same
        # connection) tells a master that it listens, as it would tell a real master.
        for serial in transport.serials.values():
            sniffer.wait_for(
                "connection",
                lambda body: body["connectionState"] == "ONLINE",
                f"ONLINE of {serial}",
                serial=serial,
            )
        return served

    yield make
    for served in made:
        served.transport.stop()
        served.fleet.close()
        served.sim.close()


# ----- masters ---------------------------------------------------------------------------------


class RawMaster:
    """A plain paho client that publishes whatever bytes a test gives it (no SDK)."""

    def __init__(self, url: str) -> None:
        address = _address(url)
        mqtt = _paho()
        self.client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=f"raw-{uuid4().hex}")
        self.client.connect(address.host, address.port, keepalive=15)
        self.client.loop_start()
        self.header_ids: dict[str, int] = {}

    def send(self, topic: str, message: bytes | dict[str, Any]) -> None:
        """Publish (QoS 1, not retained) and wait until the broker has it."""
        payload = message if isinstance(message, bytes) else json.dumps(message).encode()
        self.client.publish(topic, payload, qos=1).wait_for_publish(TIMEOUT)

    def header(self, manufacturer: str, serial: str, topic: str, version: str) -> dict[str, Any]:
        """A header: headerIds count per topic."""
        header_id = self.header_ids.get(topic, -1) + 1
        self.header_ids[topic] = header_id
        return {
            "headerId": header_id,
            "timestamp": now_iso(),
            "version": version,
            "manufacturer": manufacturer,
            "serialNumber": serial,
        }

    def close(self) -> None:
        """Disconnect."""
        self.client.disconnect()
        self.client.loop_stop()


@pytest.fixture
def raw_master(broker_url: str) -> Iterator[RawMaster]:
    """A plain paho publisher on the test's broker."""
    master = RawMaster(broker_url)
    yield master
    master.close()


def vda_order(
    header: dict[str, Any],
    order_id: str,
    points: list[tuple[str, float, float]],
    *,
    update: int = 0,
    released: int | None = None,
    first_sequence: int = 0,
    node_actions: dict[str, list[dict[str, Any]]] | None = None,
    map_id: str = "map",
) -> dict[str, Any]:
    """A VDA 5050 order through ``points`` (nodeId, x, y); the first ``released`` nodes (all
    by default) and the edges between them are the base."""
    released = len(points) if released is None else released
    actions = node_actions or {}
    nodes = [
        {
            "nodeId": node_id,
            "sequenceId": first_sequence + 2 * i,
            "released": i < released,
            "nodePosition": {"x": x, "y": y, "mapId": map_id},
            "actions": actions.get(node_id, []),
        }
        for i, (node_id, x, y) in enumerate(points)
    ]
    edges = [
        {
            "edgeId": f"{a[0]}-{b[0]}",
            "sequenceId": first_sequence + 2 * i + 1,
            "released": i + 1 < released,
            "startNodeId": a[0],
            "endNodeId": b[0],
            "actions": [],
        }
        for i, (a, b) in enumerate(pairwise(points))
    ]
    return {**header, "orderId": order_id, "orderUpdateId": update, "nodes": nodes, "edges": edges}
