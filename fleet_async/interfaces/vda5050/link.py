"""One vehicle's MQTT connection: its own client, last will, subscriptions and headerIds.

Every callback here runs on the transport's network thread (``network.py``): it connects,
subscribes to the vehicle's ``order`` and ``instantActions`` topics, announces the vehicle
(ONLINE, the factsheet) once the subscriptions are confirmed, decodes what arrives and hands
the command to the fleet interface, and asks for a reconnect when the broker is lost.
"""

from __future__ import annotations

import json
import logging
import ssl
import threading
from typing import TYPE_CHECKING, Any

from fleet_async.interfaces.commands import Rejection
from fleet_async.interfaces.vda5050 import encode
from fleet_async.interfaces.vda5050.decode import decode

if TYPE_CHECKING:
    from fleet_async.interfaces.vda5050.mqtt import MqttTransport

__all__ = ["VehicleLink"]

logger = logging.getLogger(__name__)

KEEPALIVE_S = 15
"""MQTT keepalive, as the standard suggests."""


class VehicleLink:
    """The MQTT client of one served vehicle.

    Args:
        transport: The transport it belongs to (config, address, the network loop).
        robot: The robot's name in the simulation.
        serial: Its serialNumber.
    """

    def __init__(self, transport: MqttTransport, robot: str, serial: str) -> None:
        import paho.mqtt.client as mqtt

        self.robot, self.serial = robot, serial
        self.transport = transport
        config = transport.config
        self.header = encode.Header(config, serial, transport.epoch)
        self.connected = threading.Event()
        self.topics = {name: config.topic(serial, name) for name in _TOPICS}
        client = mqtt.Client(
            mqtt.CallbackAPIVersion.VERSION2,
            client_id=f"{config.manufacturer}-{serial}-{id(self):x}"[:64],
            clean_session=True,
        )
        address = transport.address
        if address.username is not None:
            client.username_pw_set(address.username, address.password)
        if address.tls:
            client.tls_set_context(transport.tls_context or ssl.create_default_context())
        will = encode.connection(self.header.make("connection", 0.0), "CONNECTIONBROKEN")
        client.will_set(self.topics["connection"], json.dumps(will), qos=1, retain=True)
        client.on_connect = self._on_connect
        client.on_disconnect = self._on_disconnect
        client.on_subscribe = self._on_subscribe
        client.on_message = self._on_message
        self.client = client

    def connect(self) -> None:
        """Open the connection (network thread); a failure is retried with a backoff."""
        loop = self.transport.loop
        address = self.transport.address
        self.client.connect_async(address.host, address.port, keepalive=KEEPALIVE_S)
        try:
            self.client.reconnect()
        except (OSError, ValueError) as exc:
            logger.warning("%s: cannot reach the broker %s (%s)", self.serial, address.url, exc)
            loop.reconnect_later(self.client)

    def publish(self, topic: str, make: Any, qos: int = 0, retain: bool = False) -> None:
        """Publish ``make()`` on the vehicle's ``topic`` now (network thread)."""
        self.client.publish(self.topics[topic], make(), qos, retain)

    def _on_connect(self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any) -> None:
        if getattr(reason, "is_failure", False):
            logger.warning("%s: the broker refused the connection: %s", self.serial, reason)
            self.transport.loop.reconnect_later(client)
            return
        self.transport.loop.connected(client)
        client.subscribe([(self.topics["order"], 0), (self.topics["instantActions"], 0)])

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
            self.transport.loop.reconnect_later(client)

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


_TOPICS = ("order", "instantActions", "state", "visualization", "connection", "factsheet")
