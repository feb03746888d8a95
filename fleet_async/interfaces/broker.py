"""An embedded MQTT 3.1.1 broker, so a fresh clone talks MQTT with no broker service installed.

The broker is `amqtt <https://pypi.org/project/amqtt/>`_ (pure Python, asyncio; the ``vda5050``
extra), run in its own child process so that its event loop, its logging and a crash of it stay
out of the simulator's process::

    with EmbeddedBroker() as broker:  # a free port on 127.0.0.1
        client.connect(broker.host, broker.port)
        ...
        broker.restart()  # same port: clients with reconnect come back

The same broker runs in the foreground from a shell::

    python -m fleet_async.interfaces.broker --port 1883

It listens on TCP only, allows anonymous clients, and keeps retained messages and last wills in
memory (a restart forgets them, as a non-persistent Mosquitto does). amqtt's quirks that show
through are described in :class:`EmbeddedBroker`.
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import subprocess
import sys
import tempfile
import time
import weakref
from pathlib import Path
from types import TracebackType
from typing import IO, Any

from fleet_async.interfaces.broker_process import (
    AMQTT_MISSING,
    DEFAULT_HOST,
    DEFAULT_PORT,
    LISTENING,
    amqtt_installed,
    broker_config,
    broker_url,
    check_port,
    main,
    serve,
)

__all__ = [
    "AMQTT_MISSING",
    "DEFAULT_HOST",
    "DEFAULT_PORT",
    "EmbeddedBroker",
    "broker_config",
    "main",
    "serve",
]

logger = logging.getLogger(__name__)

START_TIMEOUT_S = 15.0  # how long start() waits for the child to answer an MQTT CONNECT
STOP_TIMEOUT_S = 5.0  # how long stop() waits after SIGTERM before it kills the child
_PROBE_TIMEOUT_S = 1.0
_POLL_INTERVAL_S = 0.05
_LOG_TAIL_CHARS = 4000
# The child runs broker_process.py as __main__ by its path, without importing fleet_async (whose
# package imports the simulator), and with its folder off sys.path.
_CHILD_BOOTSTRAP = (
    "import runpy, sys; del sys.argv[0]; runpy.run_path(sys.argv[0], run_name='__main__')"
)
_CHILD = Path(__file__).resolve().with_name("broker_process.py")
_ADDRESS_IN_USE = "address already in use"  # in the child's log when its port was taken
_PORT_ATTEMPTS = 3  # free ports start() tries when it picks the port itself


def _free_port(host: str) -> int:
    """A TCP port on host that is free now (the OS's pick for port 0)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as sock:
        sock.bind((host, 0))
        port: int = sock.getsockname()[1]
    return port


def _connect_packet(client_id: bytes) -> bytes:
    """An MQTT 3.1.1 CONNECT packet: clean session, no keep-alive, no credentials."""
    variable_header = b"\x00\x04MQTT" + b"\x04" + b"\x02" + b"\x00\x00"
    payload = len(client_id).to_bytes(2, "big") + client_id
    body = variable_header + payload
    return b"\x10" + bytes([len(body)]) + body  # body < 128 bytes: a one-byte length


def _probe(host: str, port: int) -> bool:
    """Whether an MQTT broker on host:port accepts a CONNECT (it answers CONNACK 0).

    A full CONNECT/CONNACK/DISCONNECT rather than a bare TCP connect: amqtt logs an error for
    a connection that closes before its CONNECT.
    """
    client_id = f"fleet-async-probe-{os.getpid()}".encode()
    try:
        with socket.create_connection((host, port), timeout=_PROBE_TIMEOUT_S) as sock:
            sock.sendall(_connect_packet(client_id))
            connack = b""
            while len(connack) < 4:
                chunk = sock.recv(4 - len(connack))
                if not chunk:
                    return False
                connack += chunk
            with contextlib.suppress(OSError):
                sock.sendall(b"\xe0\x00")  # DISCONNECT
    except OSError:
        return False
    return connack[0] == 0x20 and connack[3] == 0x00


def _read_tail(log: IO[bytes], max_chars: int) -> str:
    """The last max_chars characters written to the child's log file."""
    with contextlib.suppress(ValueError, OSError):  # ValueError: the file is closed
        log.flush()
        log.seek(0)
        text = log.read().decode("utf-8", errors="replace")
        log.seek(0, os.SEEK_END)
        return text[-max_chars:]
    return ""


def _terminate(process: subprocess.Popen[bytes], log: IO[bytes]) -> None:
    """SIGTERM the child, SIGKILL it after STOP_TIMEOUT_S, reap it and close its log."""
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            logger.warning(
                "MQTT broker (pid %d) ignored SIGTERM for %.0f s: killing it",
                process.pid,
                STOP_TIMEOUT_S,
            )
            process.kill()
            process.wait()
    log.close()


class EmbeddedBroker:
    """The amqtt MQTT broker in a child process, on 127.0.0.1 and a port of its own.

    ``start()`` returns once the broker answers an MQTT CONNECT; ``stop()`` ends and reaps it;
    ``restart()`` does both on the same port. The child stops by itself when this process dies
    (it polls its parent pid), and the child is also ended when this object is collected or the
    interpreter exits. Its stderr goes to a temporary file: see :meth:`log_tail`.

    amqtt quirks (0.12.1) that show: it treats every client of an anonymous broker as
    anonymous and keeps no session for anonymous clients, so ``clean_session=False`` does not
    bring subscriptions or queued QoS 1 messages across a reconnect (subscribe again in
    on_connect); a message goes out at the subscription's QoS, not the lower of it and the
    publish's; a QoS 1 delivery not acknowledged within 5 s is dropped. (Its leak of retained
    messages to clients that did not subscribe to them is patched: see ``_broker_class``.)

    Args:
        port: The TCP port; 0 picks a free one at the first ``start()`` (kept for restarts).
        host: The address to listen on; keep the default to stay off the network.

    Raises:
        ValueError: port is not in 0..65535 or host is empty.
    """

    def __init__(self, port: int = 0, host: str = DEFAULT_HOST) -> None:
        """Configure the broker; nothing starts until ``start()``."""
        self._port = check_port(port, allow_zero=True)
        if not host:
            raise ValueError(f"host must be a non-empty address, got {host!r}")
        self._host = host
        self._process: subprocess.Popen[bytes] | None = None
        self._log: IO[bytes] | None = None
        self._finalizer: weakref.finalize[Any, Any] | None = None

    @property
    def host(self) -> str:
        """The address the broker listens on."""
        return self._host

    @property
    def port(self) -> int:
        """The TCP port (0 before the first ``start()`` of a broker made with port=0)."""
        return self._port

    @property
    def url(self) -> str:
        """The broker's URL, ``mqtt://127.0.0.1:PORT``."""
        return broker_url(self._host, self._port)

    @property
    def running(self) -> bool:
        """Whether the child process is alive."""
        return self._process is not None and self._process.poll() is None

    @property
    def pid(self) -> int | None:
        """The child's process id while it runs, else None."""
        return self._process.pid if self.running and self._process is not None else None

    def start(self, timeout: float = START_TIMEOUT_S) -> None:
        """Start the broker and return once it accepts MQTT connections (no-op if running).

        Ready means the child logged that it listens and answered an MQTT CONNECT: another
        broker already on the port does not pass for this one.

        Args:
            timeout: Seconds to wait for the broker to answer.

        Raises:
            ModuleNotFoundError: amqtt is not installed (nothing is started).
            RuntimeError: The child exited or did not answer within timeout; the message ends
                with the tail of its stderr.
        """
        if self.running:
            return
        if not amqtt_installed():
            raise ModuleNotFoundError(AMQTT_MISSING, name="amqtt")
        self.stop()  # reap a child that died by itself
        pick_port = self._port == 0
        for attempt in range(1, (_PORT_ATTEMPTS if pick_port else 1) + 1):
            if pick_port:
                self._port = _free_port(self._host)
            problem = self._spawn(timeout)
            if problem is None:
                return
            tail = self.log_tail()
            self.stop()
            if pick_port and attempt < _PORT_ATTEMPTS and _ADDRESS_IN_USE in tail.lower():
                logger.info(
                    "port %d was taken before the broker could bind it: trying another", self._port
                )
                continue
            raise RuntimeError(f"the MQTT broker on {self.url} {problem}; its stderr:\n{tail}")

    def _spawn(self, timeout: float) -> str | None:
        """Start the child on self.port and wait for it: None once ready, else what went wrong."""
        # Append mode: the child's writes land at the end while log_tail() seeks to read.
        log = tempfile.TemporaryFile(mode="a+b", prefix="fleet-async-broker-")  # noqa: SIM115
        command = [
            sys.executable,
            "-c",
            _CHILD_BOOTSTRAP,
            str(_CHILD),
            "--host",
            self._host,
            "--port",
            str(self._port),
            "--parent-pid",
            str(os.getpid()),
        ]
        logger.debug("starting the MQTT broker: %s", " ".join(command))
        process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=log, stderr=log)
        self._process, self._log = process, log
        self._finalizer = weakref.finalize(self, _terminate, process, log)
        started = time.monotonic()
        while True:
            if LISTENING in _read_tail(log, sys.maxsize) and _probe(self._host, self._port):
                logger.info(
                    "MQTT broker listening on %s (pid %d, up in %.2f s)",
                    self.url,
                    process.pid,
                    time.monotonic() - started,
                )
                return None
            code = process.poll()
            if code is not None:
                return f"exited with status {code} before listening"
            if time.monotonic() - started > timeout:
                return f"did not accept MQTT connections within {timeout:g} s"
            time.sleep(_POLL_INTERVAL_S)

    def stop(self) -> None:
        """Stop the broker: SIGTERM, SIGKILL after a timeout, and reap it (no-op if stopped)."""
        if self._finalizer is not None:
            self._finalizer()  # runs _terminate once
        self._process = self._log = self._finalizer = None

    def restart(self, timeout: float = START_TIMEOUT_S) -> None:
        """Stop the broker and start it again on the same port (retained messages are lost).

        Args:
            timeout: Seconds to wait for the new broker to answer.
        """
        self.stop()
        self.start(timeout)

    def log_tail(self, max_chars: int = _LOG_TAIL_CHARS) -> str:
        """The end of the running broker's stderr (its log), or "" when it is not started.

        Args:
            max_chars: How many characters at most.
        """
        return "" if self._log is None else _read_tail(self._log, max_chars)

    def __enter__(self) -> EmbeddedBroker:
        """Start the broker (see :meth:`start`)."""
        self.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        """Stop the broker."""
        self.stop()

    def __repr__(self) -> str:
        """Show the URL and whether it runs."""
        state = f"running, pid {self.pid}" if self.running else "stopped"
        return f"EmbeddedBroker({self.url}, {state})"


if __name__ == "__main__":
    sys.exit(main())
