"""The embedded MQTT broker's own process: amqtt in the foreground, until SIGTERM or Ctrl+C.

``EmbeddedBroker`` (``broker.py``) runs this file as a child process, by its path and without
importing ``fleet_async`` (whose package imports the simulator: pybullet, numpy), so this module
imports only the standard library and amqtt, and its folder stays off ``sys.path``. From a shell:
``python -m fleet_async.interfaces.broker --port 1883`` runs the same broker.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import importlib.util
import logging
import os
import signal
import sys
from typing import Any

__all__ = [
    "AMQTT_MISSING",
    "DEFAULT_HOST",
    "DEFAULT_PORT",
    "LISTENING",
    "amqtt_installed",
    "broker_config",
    "broker_url",
    "check_port",
    "main",
    "serve",
]

logger = logging.getLogger(__name__)

AMQTT_MISSING = (
    'the embedded MQTT broker needs the vda5050 extra: python -m pip install -e ".[vda5050]"'
)
DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 1883
LISTENING = "MQTT broker listening on"
"""The log line ``EmbeddedBroker.start`` waits for."""
# The bound on amqtt's shutdown: it takes milliseconds, or hangs for good (0.12.1, after
# traffic, on a client's reader task); the state is in memory only, so nothing is lost by leaving.
_SHUTDOWN_TIMEOUT_S = 0.5
_PARENT_POLL_S = 0.5  # how often the child checks that its parent is alive


def broker_config(host: str, port: int) -> dict[str, Any]:
    """The amqtt (0.12) configuration: one TCP listener on host:port, anonymous clients allowed.

    No ``$SYS`` topics and no packet or event logging plugins: only the authentication plugin,
    which amqtt needs to let any client in.

    Args:
        host: The address to listen on.
        port: The TCP port to listen on.

    Returns:
        The dictionary ``amqtt.broker.Broker`` takes as its config.
    """
    return {
        "listeners": {"default": {"type": "tcp", "bind": f"{host}:{port}"}},
        "plugins": {"amqtt.plugins.authentication.AnonymousAuthPlugin": {"allow_anonymous": True}},
    }


def broker_url(host: str, port: int) -> str:
    """The mqtt:// URL of host:port (an IPv6 address in brackets)."""
    shown = f"[{host}]" if ":" in host else host
    return f"mqtt://{shown}:{port}"


def check_port(port: int, *, allow_zero: bool) -> int:
    """Return port if it is a TCP port number (0 too when allow_zero), else raise ValueError."""
    low = 0 if allow_zero else 1
    if isinstance(port, bool) or not isinstance(port, int) or not low <= port <= 65535:
        raise ValueError(f"port must be an integer in {low}..65535, got {port!r}")
    return port


def amqtt_installed() -> bool:
    """Whether the optional amqtt package can be imported."""
    return importlib.util.find_spec("amqtt") is not None


# --- the child: the broker in the foreground -------------------------------------------------


async def _watch_parent(parent_pid: int, stop: asyncio.Event) -> None:
    """Set stop once this process's parent is no longer parent_pid (the parent died)."""
    while not stop.is_set():
        if os.getppid() != parent_pid:
            logger.warning("parent process %d is gone: stopping the MQTT broker", parent_pid)
            stop.set()
            return
        await asyncio.sleep(_PARENT_POLL_S)


def _broker_class() -> type[Any]:
    """amqtt's Broker, fixed so that a client gets retained messages of its own subscriptions only.

    amqtt 0.12.1, on every CONNECT, sends the new client the retained messages matching any
    topic filter that any client subscribed to (meant for the filters of a resumed session):
    a vehicle would get, say, every other vehicle's retained ``connection`` message, and a late
    subscriber gets its own retained message twice. The override lets through only filters this
    session subscribed to, which is every call amqtt makes for a SUBSCRIBE (it records the
    subscription first).

    Raises:
        ModuleNotFoundError: amqtt is not installed.
    """
    from amqtt.broker import Broker  # the optional dependency: imported only here

    method = "_publish_retained_messages_for_subscription"
    if not hasattr(Broker, method):  # another amqtt: hope it is fixed there
        logger.warning("amqtt's Broker has no %s: running it unpatched", method)
        return Broker

    class OwnRetainedBroker(Broker):
        """Broker sending retained messages only for the client's own subscriptions."""

        async def _publish_retained_messages_for_subscription(
            self, subscription: tuple[str, int], session: Any
        ) -> None:
            """Publish the retained messages matching subscription if session holds it."""
            holders = self._subscriptions.get(subscription[0], ())
            if any(holder.client_id == session.client_id for holder, _ in holders):
                await super()._publish_retained_messages_for_subscription(subscription, session)

    return OwnRetainedBroker


async def serve(host: str, port: int, *, parent_pid: int | None = None) -> None:
    """Run the amqtt broker on host:port until SIGTERM or SIGINT (or the parent's death).

    Args:
        host: The address to listen on.
        port: The TCP port to listen on (1..65535).
        parent_pid: When given, stop as soon as this process is no longer our parent.

    Raises:
        ModuleNotFoundError: amqtt is not installed.
        amqtt.errors.BrokerError: The listener could not be opened (e.g. the port is taken).
    """
    try:
        broker_class = _broker_class()
    except ModuleNotFoundError as error:
        raise ModuleNotFoundError(AMQTT_MISSING, name="amqtt") from error

    broker = broker_class(broker_config(host, port))
    await broker.start()
    logger.info(LISTENING + " %s", broker_url(host, port))

    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    signals = (signal.SIGTERM, signal.SIGINT)
    for signum in signals:
        try:
            loop.add_signal_handler(signum, stop.set)
        except NotImplementedError:  # Windows: no signal handlers on the event loop
            signal.signal(signum, lambda *_: loop.call_soon_threadsafe(stop.set))
    watchdog = (
        asyncio.create_task(_watch_parent(parent_pid, stop)) if parent_pid is not None else None
    )
    try:
        await stop.wait()
    finally:
        for signum in signals:
            with contextlib.suppress(NotImplementedError):
                loop.remove_signal_handler(signum)
        if watchdog is not None:
            watchdog.cancel()
        logger.info("MQTT broker on %s stopping", broker_url(host, port))
        try:
            await asyncio.wait_for(broker.shutdown(), _SHUTDOWN_TIMEOUT_S)
        except asyncio.TimeoutError:
            logger.info("amqtt's shutdown hangs: leaving its tasks to be cancelled")
            # Each cancelled task would log a traceback, as if it had failed.
            logging.getLogger("amqtt").setLevel(logging.CRITICAL)


def main(argv: list[str] | None = None) -> int:
    """Run the embedded MQTT broker in the foreground (``python -m fleet_async.interfaces.broker``).

    Args:
        argv: The command line arguments (default: ``sys.argv[1:]``).

    Returns:
        The exit status: 0 after SIGTERM/SIGINT, 1 if the broker could not start, 2 if amqtt is
        missing or an argument is wrong.
    """
    parser = argparse.ArgumentParser(
        prog="python -m fleet_async.interfaces.broker",
        description="Run an MQTT 3.1.1 broker (amqtt: TCP, anonymous) until SIGTERM or Ctrl+C.",
    )
    parser.add_argument("--host", default=DEFAULT_HOST, help="address to listen on (%(default)s)")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help="TCP port (%(default)s)")
    parser.add_argument(
        "--parent-pid", type=int, default=None, help="stop when this process dies (EmbeddedBroker)"
    )
    parser.add_argument(
        "-v", "--verbose", action="store_true", help="let amqtt log every connection"
    )
    args = parser.parse_args(argv)
    try:
        check_port(args.port, allow_zero=False)
    except ValueError as error:
        parser.error(str(error))  # exits with status 2

    logging.basicConfig(
        level=logging.INFO,
        stream=sys.stderr,
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    if not args.verbose:  # amqtt logs each connection and state change at INFO
        for name in ("amqtt", "transitions"):
            logging.getLogger(name).setLevel(logging.WARNING)
    if not amqtt_installed():
        print(AMQTT_MISSING, file=sys.stderr)
        return 2

    from amqtt.errors import BrokerError

    try:
        asyncio.run(serve(args.host, args.port, parent_pid=args.parent_pid))
    except BrokerError as error:
        logger.error(
            "cannot run the MQTT broker on %s: %s", broker_url(args.host, args.port), error
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
