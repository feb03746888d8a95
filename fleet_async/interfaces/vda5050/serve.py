"""``fleet-async serve``: a scenario's robots as VDA 5050 vehicles, paced at real time.

The scenario's ``serve:`` section picks the served robots (``robots:``, default all) and sets
the :class:`Vda5050Config` keys and the ``broker``; the command line overrides them. Without a
broker URL an embedded broker is started on 127.0.0.1 (the ``vda5050`` extra ships it), on
port 1883 when nothing listens there (else a free port; the command prints it), so a fresh
clone serves a fleet with no broker installed and a master finds it at MQTT's usual address.
The scenario's missions drive the robots that are not served, in the same run.
"""

from __future__ import annotations

import logging
import math
import socket
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from fleet_async.interfaces.fleet import FleetInterface
from fleet_async.interfaces.vda5050.config import Vda5050Config
from fleet_async.interfaces.vda5050.mqtt import MqttTransport

__all__ = ["ServeSettings", "serve"]

logger = logging.getLogger(__name__)

_SERVE_ONLY_KEYS = ("robots", "broker")
EMBEDDED_VISUALIZATION_CAPACITY = 2000.0
"""Visualization messages per wall second the embedded broker carries with a subscriber
(measured: 200 vehicles at 10 Hz keep up, 500 do not; docs/performance.md)."""


@dataclass
class ServeSettings:
    """What to serve, where and how (a scenario's ``serve:`` section, then the command line).

    Args:
        robots: Names of the served robots (None: every agent).
        broker: ``mqtt://host:port``, or None for an embedded broker.
        config: Topic levels, version, rates.
    """

    robots: list[str] | None = None
    broker: str | None = None
    config: Vda5050Config = field(default_factory=Vda5050Config)

    @classmethod
    def from_section(cls, section: Mapping[str, Any], where: str) -> ServeSettings:
        """Read a scenario's ``serve:`` section.

        Raises:
            ValueError: naming ``where`` (the file), the key and the value.
        """
        data = dict(section)
        robots = data.pop("robots", None)
        if robots is not None and (
            not isinstance(robots, list) or not all(isinstance(r, str) for r in robots)
        ):
            raise ValueError(
                f"{where}: serve.robots: expected a list of robot names, got {robots!r}"
            )
        broker = data.pop("broker", None)
        if broker is not None and not isinstance(broker, str):
            raise ValueError(f"{where}: serve.broker: expected mqtt://host:port, got {broker!r}")
        try:
            config = Vda5050Config.from_dict(data, where=f"{where}: serve")
        except ValueError as exc:
            valid = sorted([*Vda5050Config.__dataclass_fields__, *_SERVE_ONLY_KEYS])
            raise ValueError(f"{exc} (serve keys: {valid})") from None
        return cls(robots, broker, config)


def serve(
    sim: Any,
    settings: ServeSettings,
    duration: float | None = None,
    *,
    username: str | None = None,
    password: str | None = None,
    on_ready: Any = None,
) -> MqttTransport:
    """Serve ``sim``'s robots until ``duration`` sim seconds passed (None: until Ctrl-C).

    Paced at ``sim.params.target_rtf`` (set it > 0: a master lives in real time). Returns the
    stopped transport (its ``stats``).

    Args:
        sim: The simulation (its scenario's missions run too).
        settings: Robots, broker, protocol settings.
        duration: Sim seconds to serve, or None.
        username: Broker user name.
        password: Broker password.
        on_ready: Called with the started transport once every vehicle is online.
    """
    from fleet_async.interfaces.broker import DEFAULT_PORT, EmbeddedBroker

    broker = None
    url = settings.broker
    if url is None:  # MQTT's own port when it is free, so masters find it without being told
        broker = EmbeddedBroker(DEFAULT_PORT if _port_free(DEFAULT_PORT) else 0)
        broker.start()
        url = broker.url
    fleet = FleetInterface(
        sim,
        settings.robots,
        state_period=settings.config.state_period,
        visualization_period=_visualization_period(sim, settings, broker is not None),
        driver="a VDA 5050 master (fleet-async serve)",
    )
    transport = MqttTransport(fleet, settings.config, url, username=username, password=password)
    try:
        transport.start()
        if on_ready is not None:
            on_ready(transport)
        _drive(sim, duration)
    except KeyboardInterrupt:
        logger.info("stopped by Ctrl-C at sim time %.1f s", sim.sim_time)
    finally:
        transport.stop()
        fleet.close()
        if broker is not None:
            broker.stop()
    return transport


def _visualization_period(sim: Any, settings: ServeSettings, embedded: bool) -> float:
    """The configured period, made longer (with a warning) where the embedded broker could
    not carry the fleet's visualization at that rate in real time."""
    period = settings.config.visualization_period
    if not embedded or period <= 0:
        return period
    served = len(settings.robots) if settings.robots is not None else len(sim.agents)
    rate = served / period * max(sim.params.target_rtf, 1e-9)  # messages per wall second
    if rate <= EMBEDDED_VISUALIZATION_CAPACITY:
        return period
    slower = served * max(sim.params.target_rtf, 1e-9) / EMBEDDED_VISUALIZATION_CAPACITY
    logger.warning(
        "%d vehicles every %g s is %.0f visualization messages a second, more than the "
        "embedded broker carries (%.0f): every %.2f s instead; --broker (mosquitto) takes the "
        "full rate",
        served, period, rate, EMBEDDED_VISUALIZATION_CAPACITY, slower,
    )  # fmt: skip
    return slower


def _port_free(port: int, host: str = "127.0.0.1") -> bool:
    """Whether nothing listens on ``host:port``."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.settimeout(0.5)
        return probe.connect_ex((host, port)) != 0


def _drive(sim: Any, duration: float | None) -> None:
    """Step (paced) with the scenario's missions, if any, for ``duration`` s or forever."""
    specs: Sequence[Any] = sim.scenario_missions
    if not specs:
        from fleet_async.core.base.steps import steps_for
        from fleet_async.core.view.runner import run_steps

        steps = None if duration is None else steps_for(duration, sim.params.timestep)
        run_steps(sim, steps)
        return
    from fleet_async.tasks import run

    end = math.inf if duration is None else sim.sim_time + duration

    async def main() -> None:
        async with sim.task_group() as group:
            for spec in specs:
                group.start_soon(spec.coroutine_function(), sim, name=spec.name)
            await sim.sleep_until(end if math.isfinite(end) else sim.sim_time + 1e9)

    run(sim, main, until=None if not math.isfinite(end) else end)
