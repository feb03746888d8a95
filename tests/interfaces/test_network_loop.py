"""The network thread's queues: states before pictures, pictures dropped first (fake clients)."""

from __future__ import annotations

import threading
from typing import Any

from fleet_async.interfaces.vda5050.network import UNSENT_LIMIT, NetworkLoop


class FakeClient:
    """A paho stand-in that records publishes; ``on_publish`` fires only when told."""

    def __init__(self) -> None:
        self.published: list[str] = []
        self.done = threading.Event()

    def publish(self, topic: str, payload: Any, qos: int, retain: bool) -> None:
        self.published.append(topic)
        if topic == "end":
            self.done.set()

    def loop_misc(self) -> None:
        """Nothing to keep alive."""

    def want_write(self) -> bool:
        return False


def run_loop(loop: NetworkLoop, client: FakeClient, items: list[tuple[str, bool]]) -> None:
    paused = threading.Event()
    loop.start()
    loop.call_soon(paused.wait)  # hold the thread while everything is queued
    for topic, visual in items:
        loop.publish(client, topic, lambda: b"{}", visualization=visual)
    loop.publish(client, "end", lambda: b"{}")
    paused.set()
    assert client.done.wait(10)
    loop.stop()


def test_states_go_out_before_visualization_queued_earlier():
    loop, client = NetworkLoop(), FakeClient()
    loop.attach(client)
    run_loop(loop, client, [("viz1", True), ("state1", False), ("viz2", True), ("state2", False)])
    assert (
        client.published == ["state1", "state2", "end", "viz1", "viz2"][:3] + client.published[3:]
    )
    assert sorted(client.published[3:]) == ["viz1", "viz2"]


def test_a_connection_that_cannot_write_drops_visualization_not_states():
    loop, client = NetworkLoop(), FakeClient()
    loop.attach(client)  # on_publish never fires: nothing this client sends is written
    items = [(f"viz{i}", True) for i in range(UNSENT_LIMIT + 10)] + [("state", False)]
    run_loop(loop, client, items)
    assert "state" in client.published and "end" in client.published
    sent = [t for t in client.published if t.startswith("viz")]
    assert len(sent) == UNSENT_LIMIT - 2  # the state and the end went first
    assert loop.stats.dropped_visualizations == 12


def test_a_full_outbox_drops_visualization_first():
    loop, client = NetworkLoop(visualization_budget=3, outbox_limit=5), FakeClient()
    results = [loop.publish(client, f"m{i}", lambda: b"", visualization=i % 2 == 0)
               for i in range(8)]  # fmt: skip
    # From 3 queued on, pictures are refused; states are taken up to 5 queued.
    assert results == [True, True, True, True, False, True, False, False]
    assert (loop.stats.dropped_visualizations, loop.stats.dropped_other) == (2, 1)
    assert not loop.alive  # never started: publishing only queued
