"""A fleet served over VDA 5050, and a small master that drives it, in one process.

Run:  python examples/served_fleet_master.py [--max-steps N] [--broker mqtt://host:port]

The scenario (scenarios/served_fleet.yaml) serves two AMRs as VDA 5050 vehicles; a mission
drives the shuttle. Without --broker an embedded MQTT broker is started on 127.0.0.1. The
master below knows nothing of fleet_async: it speaks MQTT (paho-mqtt) and VDA 5050 JSON only,
as your own fleet software would from another process. It sends each AMR a transport order
(drive to its tote, pick it, drive to the drop lane, drop it) and prints what the vehicles
report, in sim time. ``fleet-async serve scenarios/served_fleet.yaml`` serves the same fleet
for a master of your own. Needs the vda5050 extra: python -m pip install -e ".[vda5050]"
"""

from __future__ import annotations

import argparse
import itertools
import json
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCENARIO = HERE / "scenarios" / "served_fleet.yaml"


async def patrol(sim, robot: str) -> None:
    """The shuttle's mission: back and forth along the drop lane, forever."""
    from fleet_async import Pose

    shuttle = next(a for a in sim.agents if a.name == robot)
    while True:
        await shuttle.move(Pose.from_xyz(6.0, 4.0, 0.15))
        await shuttle.move(Pose.from_xyz(6.0, -4.0, 0.15))


# ----- the master: MQTT and VDA 5050 JSON only ------------------------------------------------


def transport_order(serial: str, x: float, header_id: int) -> dict:
    """Drive from (x, 0) to the tote at (x, 4), pick it, drive to (x, -4), drop it."""

    def node(node_id: str, seq: int, y: float, actions: list) -> dict:
        position = {"x": x, "y": y, "mapId": "floor"}
        return {
            "nodeId": node_id,
            "sequenceId": seq,
            "released": True,
            "nodePosition": position,
            "actions": actions,
        }

    def action(kind: str, **params: str) -> dict:
        return {
            "actionType": kind,
            "actionId": f"{serial}-{kind}",
            "blockingType": "HARD",
            "actionParameters": [{"key": k, "value": v} for k, v in params.items()],
        }

    tote = f"tote_{int(x / 2 + 1)}"
    nodes = [
        node("start", 0, 0.0, []),
        node("pick", 2, 4.0, [action("pick", loadId=tote)]),
        node("lane", 4, 0.0, []),
        node("drop", 6, -4.0, [action("drop")]),
    ]
    edges = [
        {
            "edgeId": f"e{i}",
            "sequenceId": 2 * i + 1,
            "released": True,
            "startNodeId": a["nodeId"],
            "endNodeId": b["nodeId"],
            "actions": [],
        }
        for i, (a, b) in enumerate(itertools.pairwise(nodes))
    ]
    return {
        "headerId": header_id,
        "timestamp": "2026-11-27T00:00:00.000Z",
        "version": "2.1.0",
        "manufacturer": "fleet_async",
        "serialNumber": serial,
        "orderId": f"transport-{serial}",
        "orderUpdateId": 0,
        "nodes": nodes,
        "edges": edges,
    }


class Master:
    """Listens to every vehicle's state; remembers what changed."""

    def __init__(self, host: str, port: int) -> None:
        import paho.mqtt.client as mqtt

        self.log: list[tuple[str, str, str]] = []  # (timestamp, serial, what)
        self.online: set[str] = set()
        self.done: set[str] = set()
        self._last: dict[str, tuple] = {}
        self.changed = threading.Condition()
        self.client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="example-master")
        self.client.on_message = self._on_message
        self.client.connect(host, port)
        self.client.subscribe("uagv/v2/fleet_async/+/state")
        self.client.subscribe("uagv/v2/fleet_async/+/connection")
        self.client.loop_start()

    def _on_message(self, client, userdata, message) -> None:
        body = json.loads(message.payload)
        serial = message.topic.split("/")[3]
        with self.changed:
            if message.topic.endswith("connection"):
                if body["connectionState"] == "ONLINE":
                    self.online.add(serial)
            else:
                self._on_state(serial, body)
            self.changed.notify_all()

    def _on_state(self, serial: str, state: dict) -> None:
        actions = tuple((a["actionType"], a["actionStatus"]) for a in state["actionStates"])
        loads = tuple(load["loadId"] for load in state.get("loads", []))
        now = (state["lastNodeId"], actions, loads, state["driving"])
        if now != self._last.get(serial):
            self._last[serial] = now
            what = f"at {state['lastNodeId'] or '-':5} driving={state['driving']!s:5}"
            what += f" actions={dict(actions)} loads={list(loads)}"
            self.log.append((state["timestamp"][11:23], serial, what))
        if actions and all(status == "FINISHED" for _, status in actions):
            self.done.add(serial)

    def send(self, serial: str, order: dict) -> None:
        self.client.publish(f"uagv/v2/fleet_async/{serial}/order", json.dumps(order))

    def wait_for(self, check, timeout: float = 20.0) -> bool:
        with self.changed:
            return self.changed.wait_for(check, timeout)

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


# ----- the simulation side --------------------------------------------------------------------


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--max-steps", type=int, default=600, help="steps to run (0.1 s each)")
    parser.add_argument("--broker", help="mqtt://host:port (default: an embedded broker)")
    args = parser.parse_args()
    try:
        from fleet_async.interfaces.broker import EmbeddedBroker
        from fleet_async.interfaces.vda5050 import MqttTransport, Vda5050Config
    except ModuleNotFoundError as exc:
        raise SystemExit(
            f'{exc}\nthis example needs: python -m pip install -e ".[vda5050]"'
        ) from None
    from fleet_async import MultiRobotSimulationCore, run
    from fleet_async.interfaces import FleetInterface

    sim = MultiRobotSimulationCore.from_yaml(SCENARIO)
    sim.params.target_rtf = 0.0  # the master waits for the vehicles: no need to pace
    broker = None if args.broker else EmbeddedBroker()
    if broker is not None:
        broker.start()
    url = args.broker or broker.url
    fleet = FleetInterface(sim, list(sim.scenario_serve["robots"]), visualization_period=0)
    transport = MqttTransport(fleet, Vda5050Config(epoch=0.0), url)
    transport.start()
    host, port = transport.address.host, transport.address.port
    master = Master(host, port)
    try:
        print(f"2 AMRs served as VDA 5050 vehicles on {url}; the shuttle runs a mission")
        assert master.wait_for(lambda: {"amr_0", "amr_1"} <= master.online), "vehicles offline"
        for i, (serial, x) in enumerate((("amr_0", -2.0), ("amr_1", 0.0))):
            master.send(serial, transport_order(serial, x, i))
        # Lockstep, so the run is the same every time: start stepping once both orders are in.
        deadline = time.monotonic() + 20.0
        while transport.stats.received < 2 and time.monotonic() < deadline:
            time.sleep(0.01)

        async def fleet_run(sim):
            async with sim.task_group() as group:
                group.start_soon(patrol, sim, "shuttle")
                await sim.sleep(args.max_steps * sim.params.timestep)
                group.cancel_scope.cancel()

        run(sim, fleet_run, sim)
        master.wait_for(lambda: master.done >= {"amr_0", "amr_1"}, timeout=5.0)
    finally:
        master.close()
        transport.stop()
        fleet.close()
        if broker is not None:
            broker.stop()
    print("what the master saw (sim time, vehicle, state):")
    for stamp, serial, what in sorted(master.log):
        print(f"  {stamp}  {serial}  {what}")
    shuttle = next(a for a in sim.agents if a.name == "shuttle")
    print(f"shuttle at y = {shuttle.get_pose().y:.2f} after {sim.sim_time:.1f} s of its patrol")
    totes = {o.name: o.get_pose() for o in sim.objects if o.name.startswith("tote")}
    print("totes:", ", ".join(f"{n} ({p.x:.1f}, {p.y:.1f})" for n, p in sorted(totes.items())))
    sim.close()


if __name__ == "__main__":
    main()
