"""The embedded MQTT broker: lifecycle, pub/sub, retained messages, last wills, restarts."""

from __future__ import annotations

import queue
import signal
import socket
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest

pytest.importorskip("amqtt", reason="the embedded MQTT broker needs amqtt (the vda5050 extra)")
mqtt: Any = pytest.importorskip("paho.mqtt.client", reason="the MQTT tests need paho-mqtt")

from fleet_async.interfaces import broker as broker_module  # noqa: E402
from fleet_async.interfaces.broker import AMQTT_MISSING, EmbeddedBroker  # noqa: E402

TIMEOUT = 15.0  # generous: a loaded CI machine; a passing test never waits this long
TOPIC = "fleet/test"


def _get(items: queue.Queue[Any], what: str, timeout: float = TIMEOUT) -> Any:
    """The next item of a paho callback's queue, or a test failure naming what never came."""
    try:
        return items.get(timeout=timeout)
    except queue.Empty:
        pytest.fail(f"no {what} within {timeout:g} s")


@dataclass
class Peer:
    """A paho client on its own network thread, with queues its callbacks fill."""

    client: Any
    messages: queue.Queue[Any] = field(default_factory=queue.Queue)
    connacks: queue.Queue[Any] = field(default_factory=queue.Queue)
    subacks: queue.Queue[Any] = field(default_factory=queue.Queue)
    disconnects: queue.Queue[Any] = field(default_factory=queue.Queue)

    def message(self) -> Any:
        """The next message received."""
        return _get(self.messages, f"message for {self.client._client_id!r}")


@pytest.fixture
def broker() -> Iterator[EmbeddedBroker]:
    """A running embedded broker on a free port."""
    with EmbeddedBroker() as running:
        yield running


@pytest.fixture
def connect(broker: EmbeddedBroker) -> Iterator[Callable[..., Peer]]:
    """Make connected paho clients (subscribed to the given topics); disconnected afterwards."""
    peers: list[Peer] = []

    def make(client_id: str, *topics: str, will: tuple[str, bytes] | None = None) -> Peer:
        peer = Peer(mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=client_id))
        client = peer.client
        if will is not None:
            client.will_set(will[0], will[1], qos=1)
        client.reconnect_delay_set(min_delay=1, max_delay=1)

        def on_connect(c: Any, userdata: Any, flags: Any, reason: Any, props: Any) -> None:
            for topic in topics:  # again on every reconnection: amqtt keeps no session
                c.subscribe(topic, qos=1)
            peer.connacks.put(reason)

        client.on_connect = on_connect
        client.on_subscribe = lambda c, userdata, mid, reasons, props: peer.subacks.put(reasons)
        client.on_message = lambda c, userdata, message: peer.messages.put(message)
        client.on_disconnect = lambda c, userdata, flags, reason, props: peer.disconnects.put(
            reason
        )
        client.connect(broker.host, broker.port, keepalive=10)
        client.loop_start()
        peers.append(peer)
        assert not _get(peer.connacks, f"CONNACK for {client_id!r}").is_failure
        for _ in topics:
            _get(peer.subacks, f"SUBACK for {client_id!r}")
        return peer

    yield make
    for peer in peers:
        peer.client.disconnect()
        peer.client.loop_stop()


def test_broker_starts_and_stops() -> None:
    broker = EmbeddedBroker()
    assert broker.port == 0
    assert not broker.running
    broker.start()
    try:
        assert broker.running
        assert 0 < broker.port <= 65535
        assert broker.url == f"mqtt://127.0.0.1:{broker.port}"
        assert broker_module._probe(broker.host, broker.port)
        assert "MQTT broker listening on " + broker.url in broker.log_tail()
    finally:
        broker.stop()
    assert not broker.running
    assert broker.pid is None
    with pytest.raises(ConnectionRefusedError):
        socket.create_connection((broker.host, broker.port), timeout=TIMEOUT).close()
    broker.stop()  # a second stop is a no-op


def test_context_manager_and_repr() -> None:
    with EmbeddedBroker() as broker:
        assert broker.running
        assert "running" in repr(broker)
        assert broker.url in repr(broker)
    assert not broker.running
    assert "stopped" in repr(broker)


@pytest.mark.parametrize("port", [-1, 65536, "1883", 1.5, True])
def test_bad_port_is_named(port: Any) -> None:
    with pytest.raises(ValueError, match=repr(port).replace(".", r"\.")):
        EmbeddedBroker(port)


def test_start_without_amqtt_says_how_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(broker_module, "amqtt_installed", lambda: False)
    broker = EmbeddedBroker()
    with pytest.raises(ModuleNotFoundError, match=r"vda5050 extra"):
        broker.start()
    assert not broker.running


def test_cli_without_amqtt_exits_2() -> None:
    code = (
        "import sys; sys.modules['amqtt'] = None\n"
        "from fleet_async.interfaces.broker import main\n"
        "sys.exit(main(['--port', '1']))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=TIMEOUT
    )
    assert result.returncode == 2
    assert AMQTT_MISSING in result.stderr


def _wait_until_answers(port: int) -> None:
    """Return once an MQTT broker answers on 127.0.0.1:port; fail after TIMEOUT."""
    deadline = time.monotonic() + TIMEOUT
    while not broker_module._probe("127.0.0.1", port):
        assert time.monotonic() < deadline, f"no MQTT broker answers on port {port}"
        time.sleep(0.05)


def test_cli_runs_in_the_foreground_until_sigterm() -> None:
    port = broker_module._free_port("127.0.0.1")
    process = subprocess.Popen(
        [sys.executable, "-m", "fleet_async.interfaces.broker", "--port", str(port)],
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        _wait_until_answers(port)
        process.send_signal(signal.SIGTERM)
        _, stderr = process.communicate(timeout=TIMEOUT)
    finally:
        process.kill()
        process.wait()
    assert process.returncode == 0
    assert f"MQTT broker listening on mqtt://127.0.0.1:{port}" in stderr


def test_a_taken_port_fails_with_the_brokers_stderr(broker: EmbeddedBroker) -> None:
    second = EmbeddedBroker(broker.port)
    with pytest.raises(RuntimeError, match=r"exited with status 1") as raised:
        second.start()
    assert "address already in use" in str(raised.value)
    assert not second.running
    assert broker.running


def test_a_picked_port_taken_meanwhile_is_replaced(monkeypatch: pytest.MonkeyPatch) -> None:
    with socket.socket() as squatter:
        squatter.bind(("127.0.0.1", 0))
        squatter.listen()
        taken = squatter.getsockname()[1]
        picks = iter([taken])
        real_free_port = broker_module._free_port
        monkeypatch.setattr(
            broker_module, "_free_port", lambda host: next(picks, None) or real_free_port(host)
        )
        with EmbeddedBroker() as broker:
            assert broker.port != taken
            assert broker_module._probe(broker.host, broker.port)


def test_publish_subscribe_roundtrip(connect: Callable[..., Peer]) -> None:
    subscriber = connect("subscriber", f"{TOPIC}/#")
    publisher = connect("publisher")
    publisher.client.publish(f"{TOPIC}/a", b"qos 0", qos=0)
    publisher.client.publish(f"{TOPIC}/b", b"qos 1", qos=1).wait_for_publish(TIMEOUT)
    received = {subscriber.message().payload for _ in range(2)}
    assert received == {b"qos 0", b"qos 1"}


def test_retained_message_reaches_a_late_subscriber(connect: Callable[..., Peer]) -> None:
    topic = f"{TOPIC}/retained"
    publisher = connect("publisher", topic)
    publisher.client.publish(topic, b"state", qos=1, retain=True)
    # Its own copy back means the broker has handled the PUBLISH, and so stored it.
    assert publisher.message().payload == b"state"
    late = connect("late", topic)
    message = late.message()
    assert (message.topic, message.payload, message.retain) == (topic, b"state", True)


def test_retained_messages_only_for_a_clients_own_subscriptions(
    connect: Callable[..., Peer],
) -> None:
    # amqtt 0.12.1 unpatched sends each connecting client the retained messages of everybody's
    # subscriptions: vehicle 2 would get vehicle 1's connection message, "late" gets it twice.
    connection = f"{TOPIC}/vehicle/1/connection"
    order = f"{TOPIC}/vehicle/2/order"
    master = connect("master", f"{TOPIC}/vehicle/+/connection")
    master.client.publish(connection, b"ONLINE", qos=1, retain=True)
    assert master.message().payload == b"ONLINE"  # handled, so stored
    vehicle = connect("vehicle-2", order)
    late = connect("late", connection)
    assert late.message().payload == b"ONLINE"
    master.client.publish(order, b"order", qos=1)
    master.client.publish(connection, b"marker", qos=1)
    assert vehicle.message().payload == b"order"  # the first thing it got
    assert late.message().payload == b"marker"  # no second copy of the retained message


def test_last_will_when_a_clients_socket_drops(connect: Callable[..., Peer]) -> None:
    will_topic = f"{TOPIC}/connection"
    watcher = connect("watcher", will_topic)
    victim = connect("victim", will=(will_topic, b"CONNECTIONBROKEN"))
    victim.client.loop_stop()  # paho's thread stops: no DISCONNECT, no reconnection
    victim.client.socket().shutdown(socket.SHUT_RDWR)
    message = watcher.message()
    assert (message.topic, message.payload) == (will_topic, b"CONNECTIONBROKEN")


def test_last_will_when_a_client_process_is_killed(
    broker: EmbeddedBroker, connect: Callable[..., Peer]
) -> None:
    will_topic = f"{TOPIC}/killed"
    watcher = connect("watcher", will_topic)
    code = textwrap.dedent(
        f"""
        import threading, time
        import paho.mqtt.client as mqtt
        connected = threading.Event()
        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="doomed")
        client.will_set({will_topic!r}, b"killed", qos=1)
        client.on_connect = lambda *args: connected.set()
        client.connect({broker.host!r}, {broker.port})
        client.loop_start()
        connected.wait({TIMEOUT})
        print("connected", flush=True)
        time.sleep({TIMEOUT})
        """
    )
    doomed = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert doomed.stdout is not None
        assert doomed.stdout.readline().strip() == "connected"
    finally:
        doomed.kill()
        doomed.wait()
    message = watcher.message()
    assert (message.topic, message.payload) == (will_topic, b"killed")


def test_restart_keeps_the_port_and_clients_reconnect(
    broker: EmbeddedBroker, connect: Callable[..., Peer]
) -> None:
    port, pid = broker.port, broker.pid
    subscriber = connect("subscriber", TOPIC)
    broker.restart()
    assert (broker.port, broker.running) == (port, True)
    assert broker.pid != pid
    _get(subscriber.disconnects, "disconnection seen by the subscriber")
    assert not _get(subscriber.connacks, "reconnection of the subscriber").is_failure
    _get(subscriber.subacks, "SUBACK after the reconnection")
    publisher = connect("publisher")
    publisher.client.publish(TOPIC, b"after restart", qos=1).wait_for_publish(TIMEOUT)
    assert subscriber.message().payload == b"after restart"


def test_the_broker_dies_with_its_parent() -> None:
    code = textwrap.dedent(
        """
        import time
        from fleet_async.interfaces.broker import EmbeddedBroker
        broker = EmbeddedBroker()
        broker.start()
        print(broker.port, flush=True)
        time.sleep(60)
        """
    )
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert parent.stdout is not None
        port = int(parent.stdout.readline())
        assert broker_module._probe("127.0.0.1", port)
    finally:
        parent.kill()  # SIGKILL: no finalizer runs, only the child's watchdog can notice
        parent.wait()
    deadline = time.monotonic() + TIMEOUT
    while broker_module._probe("127.0.0.1", port):
        assert time.monotonic() < deadline, f"the orphaned broker still answers on port {port}"
        time.sleep(0.1)
