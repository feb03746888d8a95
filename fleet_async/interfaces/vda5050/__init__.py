"""VDA 5050 vehicles: the fleet interface translated to the standard's messages over MQTT.

Needs the ``vda5050`` extra (paho-mqtt, jsonschema; amqtt for the embedded broker):
``python -m pip install -e ".[vda5050]"``. The translation (``decode``, ``encode``) imports
neither; the transport (``mqtt``) imports paho when it is built. docs/fleet-interfaces.md
lists the supported subset of the standard and what is refused, with its error.
"""

from fleet_async.interfaces.vda5050.config import SUPPORTED_VERSIONS, Vda5050Config
from fleet_async.interfaces.vda5050.decode import MAX_PAYLOAD_BYTES, decode
from fleet_async.interfaces.vda5050.mqtt import BrokerAddress, MqttTransport, TransportStats

__all__ = [
    "MAX_PAYLOAD_BYTES",
    "SUPPORTED_VERSIONS",
    "BrokerAddress",
    "MqttTransport",
    "TransportStats",
    "Vda5050Config",
    "decode",
]
