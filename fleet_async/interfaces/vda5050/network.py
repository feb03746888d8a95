"""One network thread for every vehicle's MQTT connection (paho-mqtt's external loop).

A served fleet has one MQTT connection per vehicle (each needs its own last will), and a fleet
may have thousands: a thread each (paho's ``loop_start``) would cost a thread switch per
message. Here one thread runs them all: it waits on every connection's socket at once
(``selectors``), reads and writes what is ready, keeps the connections alive and reconnects
the ones that dropped, with a backoff.

Every paho call happens on this thread. Other threads hand it work through two queues: calls
(``call_soon``) and messages to publish (``publish``). Visualization messages wait behind the
others and are the first dropped (and counted): when more than ``visualization_budget``
messages wait, or when a connection holds :data:`UNSENT_LIMIT` messages it could not write yet
(a broker that does not keep up), so a slow broker costs pictures, not states; past
``outbox_limit`` anything is dropped (counted). Handing a message over never blocks: the
simulation's thread appends to a deque and, when the deque was empty, wakes the network thread
with one byte.
"""

from __future__ import annotations

import contextlib
import logging
import selectors
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["NetworkLoop", "OutboxStats"]

logger = logging.getLogger(__name__)

_MISC_PERIOD_S = 0.5  # keepalive pings, timeouts and due reconnects, this often
_SELECT_TIMEOUT_S = 0.1
_BACKOFF_S = (1.0, 2.0, 4.0, 8.0)
SEND_BUFFER_BYTES = 64 * 1024
"""Each connection's socket send buffer."""
UNSENT_LIMIT = 32
"""Messages a connection may hold unwritten (a slow broker) before its visualization is
dropped instead of queued behind them."""


@dataclass
class OutboxStats:
    """What the network thread published and dropped (counts since start)."""

    published: int = 0
    dropped_visualizations: int = 0
    dropped_other: int = 0
    highest_backlog: int = 0


class NetworkLoop:
    """The thread that runs every MQTT client of a transport.

    Args:
        visualization_budget: Queued messages above which visualization is dropped.
        outbox_limit: Queued messages above which anything is dropped.
    """

    def __init__(
        self,
        visualization_budget: int = 20_000,
        outbox_limit: int = 200_000,
    ) -> None:
        self.stats = OutboxStats()
        self._budget = visualization_budget
        self._limit = outbox_limit
        self._selector = selectors.DefaultSelector()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._selector.register(self._wake_r, selectors.EVENT_READ, None)
        self._calls: deque[Callable[[], None]] = deque()
        # Two queues: states, connection and factsheet messages go out before visualization.
        self._outbox: deque[tuple[Any, str, Callable[[], bytes | str], int, bool]] = deque()
        self._visual: deque[tuple[Any, str, Callable[[], bytes | str], int, bool]] = deque()
        self._clients: list[Any] = []
        self._unsent: dict[Any, int] = {}  # per client: handed to paho, not yet written
        self._reconnect_at: dict[Any, tuple[float, int]] = {}
        self._stopping = False
        self._before_exit: Callable[[], None] | None = None
        self._thread = threading.Thread(target=self._run, name="fleet-async-mqtt", daemon=True)

    # ----- from any thread -------------------------------------------------------------------

    def start(self) -> None:
        """Start the thread."""
        self._thread.start()

    @property
    def alive(self) -> bool:
        """Whether the network thread runs."""
        return self._thread.is_alive()

    def call_soon(self, call: Callable[[], None]) -> None:
        """Run ``call`` on the network thread."""
        self._calls.append(call)
        self._wake()

    def publish(
        self,
        client: Any,
        topic: str,
        payload: Callable[[], bytes | str],
        qos: int = 0,
        retain: bool = False,
        visualization: bool = False,
    ) -> bool:
        """Queue a message; ``payload()`` is called on the network thread. False if dropped.

        Visualization messages wait behind every other message (a state is not held up by a
        fleet's worth of poses queued before it) and are the first dropped.
        """
        backlog = len(self._outbox) + len(self._visual)
        if visualization and backlog >= self._budget:
            self.stats.dropped_visualizations += 1
            return False
        if backlog >= self._limit:
            self.stats.dropped_other += 1
            return False
        (self._visual if visualization else self._outbox).append(
            (client, topic, payload, qos, retain)
        )
        if backlog == 0:
            self._wake()
        return True

    def stop(self, before_exit: Callable[[], None] | None = None, timeout: float = 10.0) -> None:
        """Publish what is queued and written, call ``before_exit`` on the network thread (a
        clean disconnect), write what it queued, and stop the thread."""
        if not self._thread.is_alive():
            return
        self._before_exit = before_exit
        self._stopping = True
        self._wake()
        self._thread.join(timeout)
        self._selector.close()
        self._wake_r.close()
        self._wake_w.close()

    def _wake(self) -> None:
        with contextlib.suppress(BlockingIOError, OSError):  # full or closed: it is awake
            self._wake_w.send(b"\0")

    # ----- clients (called on the network thread) --------------------------------------------

    def attach(self, client: Any) -> None:
        """Let this loop run ``client`` (from the network thread, before it connects)."""
        client.on_socket_open = self._on_socket_open
        client.on_socket_close = self._on_socket_close
        client.on_socket_register_write = self._on_register_write
        client.on_socket_unregister_write = self._on_unregister_write
        client.on_publish = self._on_publish
        self._clients.append(client)
        self._unsent[client] = 0

    def detach(self, client: Any) -> None:
        """Stop running ``client``."""
        if client in self._clients:
            self._clients.remove(client)
        self._reconnect_at.pop(client, None)

    def reconnect_later(self, client: Any) -> None:
        """Try ``client.reconnect()`` after a backoff (1, 2, 4, 8 s ...)."""
        _, tries = self._reconnect_at.get(client, (0.0, 0))
        delay = _BACKOFF_S[min(tries, len(_BACKOFF_S) - 1)]
        self._reconnect_at[client] = (time.monotonic() + delay, tries + 1)

    def connected(self, client: Any) -> None:
        """``client`` is connected: its backoff starts over."""
        self._reconnect_at.pop(client, None)

    def _on_publish(self, client: Any, userdata: Any, mid: Any, code: Any, props: Any) -> None:
        # QoS 0: written to the socket; QoS 1: acknowledged.
        self._unsent[client] = max(0, self._unsent.get(client, 0) - 1)

    def _on_socket_open(self, client: Any, userdata: Any, sock: Any) -> None:
        # A small send buffer makes a broker that does not keep up show soon, as messages
        # paho cannot write (a vehicle sends a few kB per second).
        with contextlib.suppress(OSError, AttributeError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER_BYTES)
        self._selector.register(sock, selectors.EVENT_READ, client)

    def _on_socket_close(self, client: Any, userdata: Any, sock: Any) -> None:
        with contextlib.suppress(KeyError, ValueError):
            self._selector.unregister(sock)

    def _on_register_write(self, client: Any, userdata: Any, sock: Any) -> None:
        with contextlib.suppress(KeyError, ValueError):
            self._selector.modify(sock, selectors.EVENT_READ | selectors.EVENT_WRITE, client)

    def _on_unregister_write(self, client: Any, userdata: Any, sock: Any) -> None:
        with contextlib.suppress(KeyError, ValueError):
            self._selector.modify(sock, selectors.EVENT_READ, client)

    # ----- the thread ------------------------------------------------------------------------

    def _run(self) -> None:
        next_misc = 0.0
        while True:
            for key, events in self._selector.select(_SELECT_TIMEOUT_S):
                client = key.data
                if client is None:
                    with contextlib.suppress(BlockingIOError, OSError):
                        self._wake_r.recv(4096)
                    continue
                if events & selectors.EVENT_READ:
                    client.loop_read()
                if events & selectors.EVENT_WRITE:
                    client.loop_write()
            self._run_calls()
            self._drain_outbox()
            now = time.monotonic()
            if now >= next_misc:
                next_misc = now + _MISC_PERIOD_S
                self._misc(now)
            if self._stopping and not self._outbox and not self._visual and not self._calls:
                self._flush()
                if self._before_exit is not None:
                    self._before_exit()
                    self._flush()
                return

    def _run_calls(self) -> None:
        while self._calls:
            call = self._calls.popleft()
            try:
                call()
            except Exception:  # one failing call must not stop the others' network
                logger.exception("MQTT network thread: a call failed")

    def _drain_outbox(self) -> None:
        outbox, visual, stats = self._outbox, self._visual, self.stats
        stats.highest_backlog = max(stats.highest_backlog, len(outbox) + len(visual))
        unsent = self._unsent
        while outbox or visual:
            queue = outbox if outbox else visual
            client, topic, payload, qos, retain = queue.popleft()
            if queue is visual and unsent.get(client, 0) >= UNSENT_LIMIT:
                stats.dropped_visualizations += 1  # the broker does not keep up: a picture less
                continue
            try:
                client.publish(topic, payload(), qos, retain)
            except Exception:
                logger.exception("MQTT network thread: publishing on %s failed", topic)
                continue
            unsent[client] = unsent.get(client, 0) + 1
            stats.published += 1

    def _misc(self, now: float) -> None:
        for client in self._clients:
            client.loop_misc()
        for client, (due, _) in list(self._reconnect_at.items()):
            if now < due:
                continue
            try:
                client.reconnect()
            except (OSError, ValueError) as exc:
                logger.debug("MQTT reconnect failed: %s", exc)
                self.reconnect_later(client)
            else:
                self._reconnect_at[client] = (now + _BACKOFF_S[-1], 99)  # until CONNACK says

    def _flush(self, timeout: float = 5.0) -> None:
        """Write what paho still holds (a stop's OFFLINE messages) before the thread ends."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and any(c.want_write() for c in self._clients):
            for key, events in self._selector.select(0.05):
                if key.data is None:
                    continue
                if events & selectors.EVENT_READ:
                    key.data.loop_read()
                if events & selectors.EVENT_WRITE:
                    key.data.loop_write()
