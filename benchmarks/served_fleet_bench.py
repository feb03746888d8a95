"""Served fleets at scale: N VDA 5050 vehicles at real time, a dispatcher, a subscriber.

The workload: N box robots (default 1,000) served as VDA 5050 vehicles (state at least every
30 s and on events, visualization every 0.1 s), paced at ``--rtf`` (1.0) for ``--duration`` s
of sim time; the example dispatcher (examples/vda5050_dispatcher.py, another process, MQTT
only) keeps half of them driving shuttle orders; a subscriber in a third process counts every
state and visualization message it receives. Reported: the achieved real-time factor (sim
time / wall time of the paced run), messages published and received per topic, drops, the
network thread's highest backlog, and the latency from the dispatcher's publish of an order to
the first state that carries it (median, p99), as JSON.

Run:  python benchmarks/served_fleet_bench.py [--n 1000] [--duration 300] [--broker URL]
      (--broker embedded starts the embedded broker; default mosquitto on 127.0.0.1:1883)
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimulationParams
from fleet_async.core.base.steps import steps_for
from fleet_async.core.view.runner import run_steps
from fleet_async.interfaces import FleetInterface
from fleet_async.interfaces.broker import EmbeddedBroker
from fleet_async.interfaces.vda5050 import MqttTransport, Vda5050Config

REPO = Path(__file__).resolve().parent.parent
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
MANUFACTURER = "bench"

SUBSCRIBER = r"""
import json, signal, sys, threading
import paho.mqtt.client as mqtt
host, port, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
counts = {"state": 0, "visualization": 0}
gaps = {"state": 0, "visualization": 0}
last = {}
ready = threading.Event()
def on_message(client, userdata, message):
    kind = message.topic.rsplit("/", 1)[1]
    counts[kind] += 1
    serial = message.topic.split("/")[3]
    header = json.loads(message.payload)["headerId"]
    before = last.get((serial, kind))
    if before is not None and header > before + 1:
        gaps[kind] += header - before - 1
    last[(serial, kind)] = header
client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="bench-subscriber")
client.on_message = on_message
client.on_subscribe = lambda *a: ready.set()
client.connect(host, port, keepalive=30)
prefix = "uagv/v2/%s/+/" % sys.argv[4]
client.subscribe([(prefix + "state", 0), (prefix + "visualization", 0)])
client.loop_start()
ready.wait(10)
print("subscribed", flush=True)
stop = threading.Event()
signal.signal(signal.SIGTERM, lambda *a: stop.set())
stop.wait()
client.loop_stop()
json.dump({"received": counts, "header_gaps": gaps}, open(out, "w"))
"""


def build(n: int, rtf: float) -> MultiRobotSimulationCore:
    params = SimulationParams(gui=False, monitor=False, timestep=0.1, target_rtf=rtf)
    sim = MultiRobotSimulationCore(params)
    columns = max(1, int(n**0.5))
    for i in range(n):
        pose = Pose.from_xyz(6.0 * (i % columns), 3.0 * (i // columns), 0.1)
        Agent.from_mesh(BOX, BOX, pose, sim_core=sim, name=f"v{i:05d}")
    return sim


def clear_retained(host: str, port: int, serials: Any) -> None:
    """Empty the retained connection and factsheet topics of the benchmark's vehicles."""
    import paho.mqtt.client as mqtt

    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="bench-cleaner")
    client.connect(host, port)
    client.loop_start()
    infos = [
        client.publish(f"uagv/v2/{MANUFACTURER}/{serial}/{topic}", b"", qos=1, retain=True)
        for serial in serials
        for topic in ("connection", "factsheet")
    ]
    for info in infos:
        info.wait_for_publish(10)
    client.loop_stop()
    client.disconnect()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=1000)
    parser.add_argument("--duration", type=float, default=300.0, help="sim seconds")
    parser.add_argument("--rtf", type=float, default=1.0)
    parser.add_argument("--broker", default="mqtt://127.0.0.1:1883", help="URL or 'embedded'")
    parser.add_argument("--fraction", type=float, default=0.5, help="vehicles driving orders")
    parser.add_argument("--visualization-period", type=float, default=0.1, help="s")
    parser.add_argument("--out", help="write the result here (JSON)")
    args = parser.parse_args()

    broker = EmbeddedBroker() if args.broker == "embedded" else None
    if broker is not None:
        broker.start()
    url = broker.url if broker is not None else args.broker
    host, port = url.split("://")[1].rsplit(":", 1)
    work = Path(tempfile.mkdtemp(prefix="served_bench_"))
    sim = build(args.n, args.rtf)
    period = args.visualization_period
    fleet = FleetInterface(sim, state_period=30.0, visualization_period=period)
    transport = MqttTransport(fleet, Vda5050Config(manufacturer=MANUFACTURER), url)
    subscriber = subprocess.Popen(
        [sys.executable, "-c", SUBSCRIBER, host, port, str(work / "sub.json"), MANUFACTURER],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert subscriber.stdout is not None
    subscriber.stdout.readline()  # subscribed
    t0 = time.perf_counter()
    transport.start(timeout=120)
    connect_s = time.perf_counter() - t0
    wall_s = args.duration / args.rtf
    dispatcher = subprocess.Popen(
        [sys.executable, str(REPO / "examples" / "vda5050_dispatcher.py"), "--broker", url,
         "--manufacturer", MANUFACTURER, "--shuttle", "3", "--fraction", str(args.fraction),
         "--duration", str(wall_s + 5), "--tick", "0.1", "--report", str(work / "disp.json")],
        stdout=subprocess.DEVNULL,
    )  # fmt: skip
    time.sleep(1.0)  # the dispatcher subscribes and hears the retained ONLINE messages
    steps = steps_for(args.duration, sim.params.timestep)
    t0 = time.perf_counter()
    run_steps(sim, steps)
    run_s = time.perf_counter() - t0
    transport.stop()
    stats, sent = transport.stats, transport.sent_summary()
    dispatcher.send_signal(signal.SIGINT)
    dispatcher.wait(60)
    time.sleep(1.0)  # the last messages reach the subscriber
    subscriber.send_signal(signal.SIGTERM)
    subscriber.wait(30)
    received: dict[str, Any] = json.loads((work / "sub.json").read_text())
    dispatched: dict[str, Any] = json.loads((work / "disp.json").read_text())
    result = {
        "vehicles": args.n,
        "broker": "embedded (amqtt)" if broker is not None else url,
        "sim_seconds": sim.sim_time,
        "wall_seconds": round(run_s, 2),
        "real_time_factor": round(sim.sim_time / run_s, 4),
        "target_rtf": args.rtf,
        "visualization_period": period,
        "connect_seconds": round(connect_s, 2),
        "states_published": sent["states_sent"],
        "states_received": received["received"]["state"],
        "visualizations_published": sent["visualizations_sent"],
        "visualizations_received": received["received"]["visualization"],
        "visualization_share_received": round(
            received["received"]["visualization"] / max(1, sent["visualizations_sent"]), 4
        ),
        "dropped_states": sent["states_dropped"],
        "dropped_visualizations": sent["visualizations_dropped"],
        "highest_backlog": sent["highest_backlog"],
        "header_gaps_at_subscriber": received["header_gaps"],
        "orders_sent": dispatched["orders_sent"],
        "orders_finished": dispatched["orders_finished"],
        "order_to_state_ms_median": dispatched["latency_ms_median"],
        "order_to_state_ms_p99": dispatched["latency_ms_p99"],
        "commands_received": stats.received,
        "cpu_count": os.cpu_count(),
    }
    fleet.close()
    sim.close()
    if broker is not None:
        broker.stop()
    else:  # a shared broker keeps retained messages: leave no vehicles behind on it
        clear_retained(host, int(port), transport.serials.values())
    text = json.dumps(result, indent=2)
    print(text)
    if args.out:
        Path(args.out).write_text(text)


if __name__ == "__main__":
    main()
