"""``fleet-async serve SCENARIO``: the scenario's robots as VDA 5050 vehicles over MQTT.

Builds the scenario, makes the robots its ``serve:`` section names (default: all) VDA 5050
vehicles on a broker (an embedded one on 127.0.0.1 unless --broker names one), and runs the
simulation paced at real time (--rtf) until --duration or Ctrl-C, which stops cleanly: each
vehicle publishes OFFLINE. The scenario's missions drive the robots that are not served.
"""

from __future__ import annotations

import argparse
import signal
import sys
from pathlib import Path
from typing import Any

from fleet_async.cli.errors import CliError

__all__ = ["EPILOG", "add_arguments", "execute"]

EPILOG = """\
examples:
  fleet-async serve examples/scenarios/warehouse.yaml                 # embedded broker
  fleet-async serve my_fleet.yaml --broker mqtt://127.0.0.1:1883      # your broker
  fleet-async serve my_fleet.yaml --robots robot_0 robot_1 --manufacturer acme
  fleet-async serve my_fleet.yaml --duration 600 --trace served.fatrace

A master then talks to uagv/v2/MANUFACTURER/SERIAL/{order,instantActions} and listens on
.../{state,visualization,connection,factsheet}; SERIAL is the robot's name unless the serve
section's serial_numbers says otherwise. docs/fleet-interfaces.md has the supported subset of
VDA 5050 and what is refused, with its error. The vda5050 extra is needed:
python -m pip install -e ".[vda5050]"
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The ``serve`` command's options."""
    parser.add_argument("scenario", help="the scenario YAML file")
    parser.add_argument(
        "--broker",
        help="mqtt://host:port (mqtts:// for TLS) of the broker; default: the scenario's "
        "serve.broker, else an embedded broker on 127.0.0.1:1883 (another free port if that "
        "one is taken; printed)",
    )
    parser.add_argument("--username", help="broker user name")
    parser.add_argument("--password", help="broker password")
    parser.add_argument(
        "--robots",
        nargs="+",
        metavar="NAME",
        help="robots to serve (default: serve.robots, else all)",
    )
    parser.add_argument("--manufacturer", help="topic level and header field (default fleet_async)")
    parser.add_argument("--interface-name", help="first topic level (default uagv)")
    parser.add_argument(
        "--protocol-version", choices=("2.0.0", "2.1.0"), help="VDA 5050 version (default 2.1.0)"
    )
    parser.add_argument(
        "--rtf", type=float, default=None, help="sim seconds per wall second (default 1.0)"
    )
    parser.add_argument(
        "--duration", type=float, default=None, help="sim seconds to serve (default: until Ctrl-C)"
    )
    parser.add_argument("--trace", metavar="FILE", help="record a trace, the commands included")


def _settings(sim: Any, path: Path, args: argparse.Namespace) -> Any:
    from dataclasses import replace

    from fleet_async.interfaces.vda5050.serve import ServeSettings

    settings = ServeSettings.from_section(sim.scenario_serve, str(path))
    overrides = {
        key: value
        for key, value in (
            ("manufacturer", args.manufacturer),
            ("interface_name", args.interface_name),
            ("version", args.protocol_version),
        )
        if value is not None
    }
    if overrides:
        settings.config = replace(settings.config, **overrides)
    if args.robots:
        settings.robots = list(args.robots)
    if args.broker:
        settings.broker = args.broker
    return settings


class _Stopped(KeyboardInterrupt):
    """Ctrl-C or SIGTERM while serving. A subclass, because CPython remembers a plain
    KeyboardInterrupt that ever crossed code it ran from a string (even once handled) and then
    exits by SIGINT instead of with the command's own exit code."""


def _interrupt(signum: int, frame: Any) -> None:
    raise _Stopped


def _messages(exc: BaseException) -> str:
    """The messages of an error, or of each error of an exception group, one per line."""
    inner = getattr(exc, "exceptions", None)
    if inner is None:
        return str(exc)
    return "\n".join(dict.fromkeys(_messages(e) for e in inner))


def execute(args: argparse.Namespace) -> int:
    """Run the ``serve`` command; return the exit code."""
    from fleet_async.cli.run import load_scenario

    rtf = 1.0 if args.rtf is None else args.rtf
    if not rtf > 0:
        raise CliError(f"--rtf: a served fleet is paced; expected a number > 0, got {rtf!r}")
    if args.duration is not None and not args.duration > 0:
        raise CliError(f"--duration: expected a number > 0 (sim seconds), got {args.duration!r}")
    path = Path(args.scenario)
    try:
        sim = load_scenario(path, False, rtf, drop_trace=bool(args.trace))
    except (ValueError, TypeError, OSError) as exc:
        raise CliError(str(exc)) from exc
    try:
        return _serve(sim, path, args)
    finally:
        sim.close()


def _serve(sim: Any, path: Path, args: argparse.Namespace) -> int:
    try:
        from fleet_async.interfaces.vda5050.serve import serve

        settings = _settings(sim, path, args)
    except (ValueError, ModuleNotFoundError) as exc:
        raise CliError(str(exc)) from exc
    if args.trace:
        sim.start_trace(args.trace)

    def ready(transport: Any) -> None:
        names = ", ".join(f"{robot} as {serial}" for robot, serial in transport.serials.items())
        print(
            f"serving {len(transport.serials)} VDA 5050 {settings.config.version} vehicle(s) on "
            f"{transport.address.url}: {names}\n"
            f"topics: {settings.config.topic('SERIAL', 'TOPIC')}; Ctrl-C stops",
            flush=True,
        )

    # SIGTERM (a service manager, `kill`) stops as cleanly as Ctrl-C: OFFLINE is published.
    previous = signal.signal(signal.SIGTERM, _interrupt)
    previous_int = signal.signal(signal.SIGINT, _interrupt)
    try:
        transport = serve(
            sim,
            settings,
            args.duration,
            username=args.username,
            password=args.password,
            on_ready=ready,
        )
    except (ValueError, ModuleNotFoundError, ConnectionError, RuntimeError) as exc:
        raise CliError(_messages(exc)) from exc
    except Exception as exc:
        if getattr(exc, "exceptions", None) is None:
            raise
        raise CliError(_messages(exc)) from exc  # missions failed: one line per error
    finally:
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, previous_int)
        if args.trace:
            sim.stop_trace()
    stats, sent = transport.stats, transport.sent_summary()
    print(
        f"stopped at sim time {sim.sim_time:.1f} s: {stats.received} messages received "
        f"({stats.rejected} refused), {sent['states_sent']} states and "
        f"{sent['visualizations_sent']} visualization messages published "
        f"({sent['states_dropped']} states and {sent['visualizations_dropped']} visualization "
        "messages dropped: vehicles offline, or a broker that did not keep up)",
        file=sys.stdout,
    )
    return 0
