"""A VDA 5050 dispatcher: random transport orders to idle vehicles, over MQTT only.

Run it beside a served fleet (two terminals):

    fleet-async serve examples/scenarios/served_warehouse.yaml --broker mqtt://127.0.0.1:1883
    python examples/vda5050_dispatcher.py --broker mqtt://127.0.0.1:1883 --duration 120

This is a master as your own fleet software would be one: it imports nothing of fleet_async,
speaks MQTT (paho-mqtt) and VDA 5050 JSON, and learns the vehicles from their ``connection``
and ``state`` topics. The layout file (``--layout``, default the served warehouse's) names the
stations (nodes where a load can stand) and the loads standing there; a transport order picks
a random load and drops it at a random free station, driving along the highway row in between.
``--shuttle D`` instead sends each vehicle back and forth D m along x (no layout; the
benchmark of served fleets uses it). ``--report FILE`` writes what it measured (orders sent and
finished, the latency from an order's publish to the first state that carries it) as JSON.

``python examples/vda5050_dispatcher.py --self-serve`` starts ``fleet-async serve`` on the
warehouse itself (its embedded broker, 20x real time) in a child process and dispatches to it,
for a quick look; ``--max-steps N`` sets that run's length (the examples' test runs every
example so).
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import sys
import threading
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
LAYOUT = HERE / "layouts" / "served_warehouse.yaml"
SCENARIO = HERE / "scenarios" / "served_warehouse.yaml"


@dataclass
class Vehicle:
    """What the dispatcher knows of one vehicle, from its messages."""

    manufacturer: str
    serial: str
    online: bool = False
    state: dict[str, Any] | None = None
    busy_with: str | None = None  # the order it was given and has not finished
    transport: tuple[str, str] | None = None  # (from station, to station)
    header_id: int = 0

    @property
    def idle(self) -> bool:
        state = self.state
        if state is None or state["driving"] or state["nodeStates"]:
            return False
        done = all(a["actionStatus"] in ("FINISHED", "FAILED") for a in state["actionStates"])
        return done and (self.busy_with is None or state["orderId"] == self.busy_with)


@dataclass
class Report:
    """What the dispatcher measured."""

    orders_sent: int = 0
    orders_finished: int = 0
    states_received: int = 0
    latencies_ms: list[float] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        lat = sorted(self.latencies_ms)
        pick = (lambda q: lat[min(len(lat) - 1, int(q * len(lat)))]) if lat else (lambda q: None)
        return {
            "orders_sent": self.orders_sent,
            "orders_finished": self.orders_finished,
            "states_received": self.states_received,
            "latency_ms_median": statistics.median(lat) if lat else None,
            "latency_ms_p99": pick(0.99),
            "latency_samples": len(lat),
        }


def now_iso() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


class Dispatcher:
    """Keeps idle vehicles busy with transport (or shuttle) orders."""

    def __init__(self, args: argparse.Namespace) -> None:
        import paho.mqtt.client as mqtt

        self.args = args
        self.rng = random.Random(args.seed)
        self.vehicles: dict[str, Vehicle] = {}
        self.report = Report()
        self.sent_at: dict[str, float] = {}
        self.lock = threading.Lock()
        self.layout = load_layout(args.layout) if not args.shuttle else None
        self.loads = dict(self.layout["loads"]) if self.layout else {}  # station -> load id
        self.reserved: set[str] = set()
        self.count = 0
        host, port = parse_broker(args.broker)
        self.client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="fa-dispatcher")
        self.client.on_connect = self._on_connect
        self.client.on_message = self._on_message
        self.client.connect(host, port, keepalive=15)
        self.client.loop_start()

    def _on_connect(self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any) -> None:
        prefix = f"{self.args.interface}/v2/{self.args.manufacturer}/+"
        client.subscribe([(f"{prefix}/connection", 1), (f"{prefix}/state", 0)])

    def _on_message(self, client: Any, userdata: Any, message: Any) -> None:
        received = time.monotonic()
        parts = message.topic.split("/")
        if len(parts) != 5:
            return
        try:
            body = json.loads(message.payload)
        except ValueError:
            return
        with self.lock:
            vehicle = self.vehicles.setdefault(parts[3], Vehicle(parts[2], parts[3]))
            if parts[4] == "connection":
                vehicle.online = body.get("connectionState") == "ONLINE"
                return
            self.report.states_received += 1
            vehicle.state = body
            sent = self.sent_at.pop(body.get("orderId", ""), None)
            if sent is not None:
                self.report.latencies_ms.append((received - sent) * 1000.0)

    # ----- orders ----------------------------------------------------------------------------

    def managed(self) -> list[Vehicle]:
        """The vehicles this dispatcher drives: ``--fraction`` of the online ones, by serial."""
        online = sorted((v for v in self.vehicles.values() if v.online), key=lambda v: v.serial)
        return online[: round(len(online) * self.args.fraction)]

    def tick(self) -> None:
        """Give every idle managed vehicle its next order."""
        with self.lock:
            for vehicle in self.managed():
                if not vehicle.idle:
                    continue
                if vehicle.busy_with is not None:
                    self.report.orders_finished += 1
                    self._finish_transport(vehicle)
                    vehicle.busy_with = None
                order = self._next_order(vehicle)
                if order is not None:
                    self._send(vehicle, order)

    def _finish_transport(self, vehicle: Vehicle) -> None:
        if vehicle.transport is None:
            return
        source, target = vehicle.transport
        self.loads[target] = self.loads.pop(source)
        self.reserved -= {source, target}
        vehicle.transport = None

    def _next_order(self, vehicle: Vehicle) -> list[tuple[str, float, float, list]] | None:
        assert vehicle.state is not None
        position = vehicle.state.get("agvPosition") or {"x": 0.0, "y": 0.0}
        x, y = float(position["x"]), float(position["y"])
        here = vehicle.state["lastNodeId"] or f"{vehicle.serial}-start"
        if self.args.shuttle:
            far = (x + self.args.shuttle, y) if self.count % 2 == 0 else (x - self.args.shuttle, y)
            return [(here, x, y, []), (f"{vehicle.serial}-far", *far, []), (here, x, y, [])]
        return self._transport(vehicle, here, x, y)

    def _transport(self, vehicle: Vehicle, here: str, x: float, y: float) -> list | None:
        stations = self.layout["stations"]
        full = [s for s in self.loads if s not in self.reserved]
        free = [s for s in stations if s not in self.loads and s not in self.reserved]
        if not full or not free:
            return None
        source, target = self.rng.choice(sorted(full)), self.rng.choice(sorted(free))
        self.reserved |= {source, target}
        vehicle.transport = (source, target)
        lane = float(self.layout["highway_y"])
        (sx, sy), (tx, ty) = stations[source], stations[target]
        pick = action(vehicle, "pick", loadId=self.loads[source])
        drop = action(vehicle, "drop")
        if abs(sx - x) + abs(sy - y) < 0.5:  # the load stands where the vehicle is
            points = [(source, x, y, [pick])]
        else:
            points = [(here, x, y, []), (None, x, lane, []), (None, sx, lane, []),
                      (source, sx, sy, [pick])]  # fmt: skip
        points += [(None, sx, lane, []), (None, tx, lane, []), (target, tx, ty, [drop])]
        route = [points[0]]
        for node in points[1:]:  # no two nodes in a row at one place
            if abs(node[1] - route[-1][1]) + abs(node[2] - route[-1][2]) > 1e-6:
                route.append(node)
        return route

    def _send(self, vehicle: Vehicle, route: list) -> None:
        self.count += 1
        order_id = f"order-{self.count}"
        nodes, edges = [], []
        for i, (node_id, x, y, actions) in enumerate(route):
            nodes.append({
                "nodeId": node_id or f"{order_id}-n{i}", "sequenceId": 2 * i, "released": True,
                "nodePosition": {"x": x, "y": y, "mapId": "warehouse"}, "actions": actions,
            })  # fmt: skip
            if i:
                edges.append({
                    "edgeId": f"{order_id}-e{i}", "sequenceId": 2 * i - 1, "released": True,
                    "startNodeId": nodes[-2]["nodeId"], "endNodeId": nodes[-1]["nodeId"],
                    "actions": [],
                })  # fmt: skip
        vehicle.header_id += 1
        body = {
            "headerId": vehicle.header_id, "timestamp": now_iso(), "version": "2.1.0",
            "manufacturer": vehicle.manufacturer, "serialNumber": vehicle.serial,
            "orderId": order_id, "orderUpdateId": 0, "nodes": nodes, "edges": edges,
        }  # fmt: skip
        topic = f"{self.args.interface}/v2/{vehicle.manufacturer}/{vehicle.serial}/order"
        self.sent_at[order_id] = time.monotonic()
        self.client.publish(topic, json.dumps(body), qos=0)
        vehicle.busy_with = order_id
        self.report.orders_sent += 1
        if self.args.verbose:
            where = " -> ".join(n["nodeId"] for n in nodes)
            print(f"{vehicle.serial}: {order_id} {where}", flush=True)

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


def action(vehicle: Vehicle, kind: str, **params: str) -> dict[str, Any]:
    return {
        "actionType": kind, "actionId": f"{vehicle.serial}-{kind}-{time.monotonic_ns()}",
        "blockingType": "HARD",
        "actionParameters": [{"key": k, "value": v} for k, v in params.items()],
    }  # fmt: skip


def load_layout(path: str) -> dict[str, Any]:
    import yaml

    data = yaml.safe_load(Path(path).read_text())
    stations = {name: (float(x), float(y)) for name, (x, y) in data["stations"].items()}
    return {"highway_y": data["highway_y"], "stations": stations, "loads": data["loads"]}


def parse_broker(url: str) -> tuple[str, int]:
    rest = url.split("://", 1)[-1]
    host, _, port = rest.rpartition(":")
    return (host or rest), int(port) if port.isdigit() else 1883


def run(args: argparse.Namespace) -> Report:
    dispatcher = Dispatcher(args)
    end = time.monotonic() + args.duration
    try:
        while time.monotonic() < end:
            dispatcher.tick()
            time.sleep(args.tick)
    except KeyboardInterrupt:
        pass
    finally:
        dispatcher.close()
    return dispatcher.report


def self_serve(args: argparse.Namespace) -> None:
    """Start ``fleet-async serve`` on the warehouse (its embedded broker, sped up) in a child
    process, dispatch to it until it stops, and print what happened."""
    import subprocess

    rtf, sim_seconds = 20.0, args.max_steps * 0.1
    command = [sys.executable, "-m", "fleet_async", "serve", str(SCENARIO), "--rtf", str(rtf),
               "--duration", str(sim_seconds)]  # fmt: skip
    server = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
    assert server.stdout is not None
    first = server.stdout.readline()
    print(first.strip(), flush=True)
    broker = next((w.rstrip(":") for w in first.split() if w.startswith("mqtt://")), None)
    if broker is None:
        server.kill()
        raise SystemExit(f"fleet-async serve did not start: {first}{server.stdout.read()}")
    args.broker, args.duration = broker, sim_seconds / rtf
    report = run(args)
    rest = server.stdout.read()
    server.wait()
    print(rest.strip())
    summary = report.summary()
    print(f"dispatcher: {summary['orders_sent']} transport orders sent, "
          f"{summary['orders_finished']} finished; order to state: median "
          f"{summary['latency_ms_median'] or 0:.0f} ms")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--broker", default="mqtt://127.0.0.1:1883")
    parser.add_argument("--manufacturer", default="+", help="whose vehicles (default: all)")
    parser.add_argument("--interface", default="uagv")
    parser.add_argument("--layout", default=str(LAYOUT))
    parser.add_argument("--shuttle", type=float, default=0.0, help="shuttle D m instead")
    parser.add_argument("--fraction", type=float, default=1.0, help="share of vehicles driven")
    parser.add_argument("--duration", type=float, default=60.0, help="wall seconds")
    parser.add_argument("--tick", type=float, default=0.05, help="wall s between looks")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--report", help="write the measurements here (JSON)")
    parser.add_argument("--verbose", action="store_true", help="print every order")
    parser.add_argument("--self-serve", action="store_true", help="serve the warehouse here")
    parser.add_argument("--max-steps", type=int, default=3000, help="--self-serve: steps")
    args = parser.parse_args()
    if args.self_serve or "--max-steps" in sys.argv:
        args.verbose = True
        self_serve(args)
        return
    report = run(args)
    summary = report.summary()
    print(json.dumps(summary, indent=2))
    if args.report:
        Path(args.report).write_text(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main()
