"""Served robots as VDA 5050 vehicles on an MQTT broker (paho-mqtt, the ``vda5050`` extra).

One MQTT connection per vehicle, as on real vehicles: each has its own last will (its
``connection`` topic, CONNECTIONBROKEN), publishes ONLINE and its factsheet (both retained)
each time it connects, and subscribes to its ``order`` and ``instantActions`` topics. paho's
network thread receives a message, decodes and validates it there (off the simulation's
thread) and hands the command to :meth:`FleetInterface.submit`; the simulation applies it at
its next step boundary. States go out from the simulation's thread through paho's queue, so a
step never waits on the network; while a vehicle is disconnected, paho reconnects it (with
backoff) and what it would have published is counted as dropped.
"""

from __future__ import annotations

import contextlib
import json
import logging
import ssl
import threading
import time
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit

from fleet_async.interfaces.commands import Rejection
from fleet_async.interfaces.fleet import FleetInterface
from fleet_async.interfaces.snapshot import VehicleSnapshot
from fleet_async.interfaces.vda5050 import encode
from fleet_async.interfaces.vda5050.config import Vda5050Config
from fleet_async.interfaces.vda5050.decode import decode
from fleet_async.interfaces.vda5050.factsheet import describe

__all__ = ["BrokerAddress", "MqttTransport", "TransportStats"]

logger = logging.getLogger(__name__)

_EXTRA_MISSING = (
    "serving VDA 5050 vehicles over MQTT needs the vda5050 extra: "
    'python -m pip install -e ".[vda5050]"'
)


@dataclass(frozen=True)
class BrokerAddress:
    """Where the broker is: ``mqtt://host:port`` (``mqtts://`` for TLS).

    Raises:
        ValueError: for another scheme, a missing host or a bad port, naming the URL.
    """

    host: str
    port: int
    tls: bool = False
    username: str | None = None
    password: str | None = None

    @classmethod
    def parse(cls, url: str) -> BrokerAddress:
        """Read ``mqtt://[user[:password]@]host[:port]``."""
        parts = urlsplit(url if "://" in url else f"mqtt://{url}")
        if parts.scheme not in ("mqtt", "mqtts", "tcp", "ssl"):
            raise ValueError(f"broker {url!r}: expected mqtt://host:port or mqtts://host:port")
        try:
            port = parts.port
        except ValueError:
            raise ValueError(f"broker {url!r}: the port is not a number in 0-65535") from None
        if not parts.hostname:
            raise ValueError(f"broker {url!r}: no host")
        tls = parts.scheme in ("mqtts", "ssl")
        return cls(
            parts.hostname, port or (8883 if tls else 1883), tls, parts.username, parts.password
        )

    @property
    def url(self) -> str:
        """The address as a URL (without credentials)."""
        return f"{'mqtts' if self.tls else 'mqtt'}://{self.host}:{self.port}"


@dataclass
class TransportStats:
    """What the transport did (counts since start)."""

    states: int = 0
    visualizations: int = 0
    dropped_states: int = 0
    dropped_visualizations: int = 0
    received: int = 0
    rejected: int = 0
    connects: int = 0


class _Link:
    """One vehicle's MQTT connection."""

    def __init__(self, transport: MqttTransport, robot: str, serial: str) -> None:
        import paho.mqtt.client as mqtt

        self.robot, self.serial = robot, serial
        self.transport = transport
        config = transport.config
        self.header = encode.Header(config, serial, transport.epoch)
        self.connected = threading.Event()
        client = mqtt.Client(
            mqtt.CallbackAPIVersion.VERSION2,
            client_id=f"{config.manufacturer}-{serial}-{id(self):x}"[:64],
            clean_session=True,
        )
        address = transport.address
        if address.username is not None:
            client.username_pw_set(address.username, address.password)
        if address.tls:
            context = transport.tls_context or ssl.create_default_context()
            client.tls_set_context(context)
        will = encode.connection(self.header.make("connection", 0.0), "CONNECTIONBROKEN")
        client.will_set(config.topic(serial, "connection"), json.dumps(will), qos=1, retain=True)
        client.reconnect_delay_set(min_delay=1, max_delay=8)
        client.on_connect = self._on_connect
        client.on_disconnect = self._on_disconnect
        client.on_subscribe = self._on_subscribe
        client.on_message = self._on_message
        self.client = client

    def _on_connect(self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any) -> None:
        if getattr(reason, "is_failure", False):
            logger.warning("%s: the broker refused the connection: %s", self.serial, reason)
            return
        config = self.transport.config
        topics = [config.topic(self.serial, name) for name in ("order", "instantActions")]
        client.subscribe([(topic, 0) for topic in topics])

    def _on_subscribe(self, client: Any, userdata: Any, mid: Any, codes: Any, props: Any) -> None:
        # Online once the broker confirmed the subscriptions: what a master sends after the
        # ONLINE message is heard.
        self.transport.announce(self)
        self.transport.stats.connects += 1
        self.connected.set()

    def _on_disconnect(
        self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any
    ) -> None:
        self.connected.clear()
        if not self.transport.stopping:
            logger.warning("%s: lost the broker (%s); reconnecting", self.serial, reason)

    def _on_message(self, client: Any, userdata: Any, message: Any) -> None:
        topic = message.topic.rsplit("/", 1)[-1]
        try:
            command = decode(topic, bytes(message.payload), self.transport.config, self.serial)
        except Exception as exc:  # a message must never take the vehicle's link down
            logger.exception("%s: a %s message could not be read", self.serial, topic)
            command = Rejection(
                "validation",
                f"{topic}: could not be read ({type(exc).__name__}: {str(exc)[:160]})",
                (("topic", topic),),
            )
        stats = self.transport.stats
        stats.received += 1
        if isinstance(command, Rejection):
            stats.rejected += 1
        self.transport.fleet.submit(self.robot, command)

    def publish(self, topic: str, body: dict[str, Any], qos: int = 0, retain: bool = False) -> bool:
        """Queue a message; False when the vehicle is not connected (nothing queued)."""
        if not self.connected.is_set():
            return False
        info = self.client.publish(
            self.transport.config.topic(self.serial, topic), json.dumps(body), qos, retain
        )
        return bool(info.rc == 0)


class MqttTransport:
    """Serve a fleet interface's vehicles over VDA 5050 on an MQTT broker.

    Args:
        fleet: The served vehicles.
        config: Protocol version, topic levels, serial numbers, rates.
        broker: ``mqtt://host:port`` (``mqtts://`` for TLS; ``user:password@`` allowed).
        username: Broker user name (overrides the URL's).
        password: Broker password.
        tls_context: TLS settings for ``mqtts://`` (default: the system's trust store).
    """

    def __init__(
        self,
        fleet: FleetInterface,
        config: Vda5050Config | None = None,
        broker: str = "mqtt://127.0.0.1:1883",
        *,
        username: str | None = None,
        password: str | None = None,
        tls_context: ssl.SSLContext | None = None,
    ) -> None:
        try:
            import paho.mqtt.client  # noqa: F401
        except ModuleNotFoundError as exc:
            raise ModuleNotFoundError(_EXTRA_MISSING) from exc
        self.fleet = fleet
        self.config = config if config is not None else Vda5050Config()
        address = BrokerAddress.parse(broker)
        if username is not None:
            address = BrokerAddress(address.host, address.port, address.tls, username, password)
        self.address = address
        self.tls_context = tls_context
        self.epoch = self.config.epoch if self.config.epoch is not None else time.time()
        self.stats = TransportStats()
        self.stopping = False
        self.serials = self.config.assign_serials(list(fleet.vehicles))
        self._map_ids: dict[str, str] = {}
        # What each vehicle is, read now on the simulation's thread (a reconnect republishes it
        # from paho's thread, which must not touch the simulation).
        self._factsheets = {
            robot: describe(fleet.vehicles[robot].agent, self.config) for robot in self.serials
        }
        self._links = {robot: _Link(self, robot, serial) for robot, serial in self.serials.items()}
        self._started = False

    # ----- lifecycle ----------------------------------------------------------------------

    def start(self, timeout: float = 15.0) -> None:
        """Connect every vehicle and wait until all are online.

        Raises:
            ConnectionError: when the broker does not answer within ``timeout`` s (naming it).
        """
        for link in self._links.values():
            try:
                link.client.connect_async(self.address.host, self.address.port, keepalive=15)
            except (OSError, ValueError) as exc:
                raise ConnectionError(f"MQTT broker {self.address.url}: {exc}") from exc
            link.client.loop_start()
        self._started = True
        self.stopping = False
        self.fleet.add_listener(self)
        deadline = time.monotonic() + timeout
        for link in self._links.values():
            if not link.connected.wait(max(0.0, deadline - time.monotonic())):
                self.stop(graceful=False)
                raise ConnectionError(
                    f"MQTT broker {self.address.url} did not accept vehicle {link.serial!r} "
                    f"within {timeout:g} s (is a broker running there? `fleet-async serve` "
                    "without --broker starts an embedded one)"
                )

    def stop(self, graceful: bool = True) -> None:
        """Publish OFFLINE (graceful), disconnect every vehicle and stop the network threads."""
        if not self._started:
            return
        self._started = False
        self.stopping = True
        self.fleet.remove_listener(self)
        infos = []
        for link in self._links.values():
            if graceful and link.connected.is_set():
                body = encode.connection(self._header(link, "connection"), "OFFLINE")
                infos.append(
                    link.client.publish(
                        self.config.topic(link.serial, "connection"), json.dumps(body), 1, True
                    )
                )
        for info in infos:
            # RuntimeError / ValueError: not connected any more, nothing to wait for.
            with contextlib.suppress(RuntimeError, ValueError):
                info.wait_for_publish(timeout=5.0)
        for link in self._links.values():
            link.client.disconnect()
            link.client.loop_stop()

    def __enter__(self) -> MqttTransport:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ----- what vehicles say ------------------------------------------------------------------

    def _header(self, link: _Link, topic: str) -> dict[str, Any]:
        return link.header.make(topic, self.fleet.sim.sim_time)

    def _map_id(self, robot: str) -> str:
        if self.config.map_id is not None:
            return self.config.map_id
        return self.fleet.vehicles[robot].map_id or "map"

    def announce(self, link: _Link) -> None:
        """ONLINE and the factsheet, retained (on every connect: after a broker restart too)."""
        body = encode.connection(self._header(link, "connection"), "ONLINE")
        link.client.publish(self.config.topic(link.serial, "connection"), json.dumps(body), 1, True)
        self._publish_factsheet(link)

    def _publish_factsheet(self, link: _Link) -> None:
        body = {**self._header(link, "factsheet"), **self._factsheets[link.robot]}
        link.client.publish(self.config.topic(link.serial, "factsheet"), json.dumps(body), 0, True)

    def on_state(self, snapshot: VehicleSnapshot, reasons: tuple[str, ...]) -> None:
        """Publish a state (FleetListener)."""
        link = self._links[snapshot.name]
        if not link.connected.is_set():  # headerIds count sent messages only
            self.stats.dropped_states += 1
            return
        header = self._header(link, "state")
        body = encode.state(header, snapshot, self._map_id(snapshot.name), self.config.version)
        if link.publish("state", body):
            self.stats.states += 1
        else:
            self.stats.dropped_states += 1

    def on_visualization(self, snapshot: VehicleSnapshot) -> None:
        """Publish a visualization message (FleetListener)."""
        link = self._links[snapshot.name]
        if not link.connected.is_set():
            self.stats.dropped_visualizations += 1
            return
        body = encode.visualization(
            self._header(link, "visualization"), snapshot, self._map_id(snapshot.name)
        )
        if link.publish("visualization", body):
            self.stats.visualizations += 1
        else:
            self.stats.dropped_visualizations += 1

    def on_factsheet_request(self, vehicle: str) -> None:
        """Publish the factsheet again (FleetListener)."""
        link = self._links[vehicle]
        if link.connected.is_set():
            self._publish_factsheet(link)
