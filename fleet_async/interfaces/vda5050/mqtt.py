"""Served robots as VDA 5050 vehicles on an MQTT broker (paho-mqtt, the ``vda5050`` extra).

One MQTT connection per vehicle, as on real vehicles (``link.py``): each has its own last will
(its ``connection`` topic, CONNECTIONBROKEN), publishes ONLINE and its factsheet (both
retained) each time it connects, and subscribes to its ``order`` and ``instantActions``
topics. One network thread runs every connection (``network.py``): it receives a message,
decodes and validates it there (off the simulation's thread) and hands the command to
:meth:`FleetInterface.submit`; the simulation applies it at its next step boundary. States and
visualization messages are queued by the simulation's thread and encoded and sent by the
network thread, so a step never waits on the network; a slow broker costs visualization
messages first; while a vehicle is disconnected it is reconnected with a backoff and what it
would have published is counted as dropped.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import ssl
import time
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit

from fleet_async.interfaces.fleet import FleetInterface
from fleet_async.interfaces.snapshot import VehiclePose, VehicleSnapshot
from fleet_async.interfaces.vda5050 import encode
from fleet_async.interfaces.vda5050.config import Vda5050Config
from fleet_async.interfaces.vda5050.factsheet import describe
from fleet_async.interfaces.vda5050.link import VehicleLink
from fleet_async.interfaces.vda5050.network import NetworkLoop

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
    """What the transport did (counts since start).

    ``states`` and ``visualizations`` count messages handed to the network thread;
    ``dropped_*`` those a vehicle did not send because it was offline, plus (``sent_summary``)
    the visualization messages the network thread dropped because the broker did not keep up.
    """

    states: int = 0
    visualizations: int = 0
    dropped_states: int = 0
    dropped_visualizations: int = 0
    received: int = 0
    rejected: int = 0
    connects: int = 0


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
        graph = getattr(fleet.sim, "route_graph", None)
        if self.config.route_graph is None and graph is not None:  # orders may name its nodes
            self.config = dataclasses.replace(self.config, route_graph=graph)
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
        self.loop = NetworkLoop()
        self._links = {
            robot: VehicleLink(self, robot, serial) for robot, serial in self.serials.items()
        }
        for link in self._links.values():
            self.loop.attach(link.client)
        self._started = False

    # ----- lifecycle ----------------------------------------------------------------------

    def start(self, timeout: float = 15.0) -> None:
        """Connect every vehicle and wait until all are online.

        Raises:
            ConnectionError: when the broker does not answer within ``timeout`` s (naming it).
        """
        if self._started:
            return
        self._started = True
        self.stopping = False
        self.loop.start()
        for link in self._links.values():
            self.loop.call_soon(link.connect)
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
        """Publish what is queued and OFFLINE (graceful), then disconnect every vehicle."""
        if not self._started:
            return
        self._started = False
        self.stopping = True
        self.fleet.remove_listener(self)
        links = list(self._links.values())

        def offline() -> None:
            for link in links:
                if graceful and link.connected.is_set():
                    body = encode.connection(self._header(link, "connection"), "OFFLINE")
                    link.publish("connection", lambda body=body: json.dumps(body), 1, True)

        def disconnect() -> None:
            for link in links:
                link.client.disconnect()
                link.connected.clear()

        self.loop.call_soon(offline)
        self.loop.stop(before_exit=disconnect)

    def __enter__(self) -> MqttTransport:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def sent_summary(self) -> dict[str, int]:
        """States and visualization messages sent and dropped, the network thread's drops in."""
        stats, loop = self.stats, self.loop.stats
        return {
            "states_sent": stats.states - loop.dropped_other,
            "states_dropped": stats.dropped_states + loop.dropped_other,
            "visualizations_sent": stats.visualizations - loop.dropped_visualizations,
            "visualizations_dropped": stats.dropped_visualizations + loop.dropped_visualizations,
            "highest_backlog": loop.highest_backlog,
        }

    # ----- what vehicles say ------------------------------------------------------------------

    def _header(self, link: VehicleLink, topic: str) -> dict[str, Any]:
        return link.header.make(topic, self.fleet.sim.sim_time)

    def _map_id(self, robot: str) -> str:
        if self.config.map_id is not None:
            return self.config.map_id
        return self.fleet.vehicles[robot].map_id or "map"

    def announce(self, link: VehicleLink) -> None:
        """ONLINE and the factsheet, retained (network thread; on every connect)."""
        body = encode.connection(self._header(link, "connection"), "ONLINE")
        link.publish("connection", lambda: json.dumps(body), 1, True)
        self._publish_factsheet(link)

    def _publish_factsheet(self, link: VehicleLink) -> None:
        body = {**self._header(link, "factsheet"), **self._factsheets[link.robot]}
        link.publish("factsheet", lambda: json.dumps(body), 0, True)

    def on_state(self, snapshot: VehicleSnapshot, reasons: tuple[str, ...]) -> None:
        """Queue a state (FleetListener; encoded and sent on the network thread)."""
        link = self._links[snapshot.name]
        if not link.connected.is_set():  # headerIds count sent messages only
            self.stats.dropped_states += 1
            return
        header = self._header(link, "state")
        map_id, version = self._map_id(snapshot.name), self.config.version

        def make() -> str:
            return json.dumps(encode.state(header, snapshot, map_id, version))

        if self.loop.publish(link.client, link.topics["state"], make):
            self.stats.states += 1
        else:
            self.stats.dropped_states += 1

    def on_visualization(self, pose: VehiclePose) -> None:
        """Queue a visualization message (FleetListener); dropped first under overload."""
        link = self._links[pose.name]
        if not link.connected.is_set():
            self.stats.dropped_visualizations += 1
            return
        header = self._header(link, "visualization")
        map_id = self._map_id(pose.name)

        def make() -> str:
            return json.dumps(encode.visualization(header, pose, map_id))

        topic = link.topics["visualization"]
        if self.loop.publish(link.client, topic, make, visualization=True):
            self.stats.visualizations += 1
        else:
            self.stats.dropped_visualizations += 1

    def on_factsheet_request(self, vehicle: str) -> None:
        """Publish the factsheet again (FleetListener)."""
        link = self._links[vehicle]
        if link.connected.is_set():  # stamped now, at the step that answers the request
            body = {**self._header(link, "factsheet"), **self._factsheets[link.robot]}
            # Through the outbox: after the state that reports the request FINISHED.
            self.loop.publish(link.client, link.topics["factsheet"], lambda: json.dumps(body),
                              0, True)  # fmt: skip
