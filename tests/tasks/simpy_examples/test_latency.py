"""Event latency (SimPy example ``latency``): a cable that delays every message.

A sender puts a message on a cable every few seconds; the cable carries each one in a process
of its own that waits out the cable's delay and then drops the message into a Store, from
which a receiver takes it. Nothing is random. With a delay that is a multiple of the sending
period, a message arrives in the very step the next one is sent, so the log checks how those
same-time events are ordered; a delay shorter than the period checks the plain case.
"""

from __future__ import annotations

import pytest
import simpy

import fleet_async as fa

PERIOD = 5.0  # s between two messages
SIM_TIME = 100.0  # s


def simpy_cable(delay: float, period: float) -> list[tuple]:
    env = simpy.Environment()
    wire = simpy.Store(env)
    log: list[tuple] = []

    def carry(message: tuple):
        yield env.timeout(delay)
        wire.put(message)

    def sender():
        while True:
            yield env.timeout(period)
            env.process(carry(("sent at", env.now)))
            log.append((env.now, "sender", "sends"))

    def receiver():
        while True:
            message = yield wire.get()
            log.append((env.now, "receiver", message))

    env.process(sender())
    env.process(receiver())
    env.run(until=SIM_TIME)
    return log


async def mission_cable(sim, delay: float, period: float, log: list[tuple]) -> None:
    wire = fa.Store(sim)

    async def carry(message: tuple) -> None:
        await sim.timeout(delay)
        wire.put(message)

    async def sender() -> None:
        while True:
            await sim.timeout(period)
            sim.spawn(carry, ("sent at", sim.now), name="cable")
            log.append((sim.now, "sender", "sends"))

    async def receiver() -> None:
        while True:
            message = await wire.get()
            log.append((sim.now, "receiver", message))

    sim.spawn(sender, name="sender")
    sim.spawn(receiver, name="receiver")


@pytest.mark.parametrize("delay", [10.0, 2.5], ids=lambda d: f"delay={d}")
def test_latency_logs_match_simpy(delay, on_grid, run_missions):
    delay, period = on_grid(delay), on_grid(PERIOD)
    expected = simpy_cable(delay, period)
    log: list[tuple] = []
    run_missions(mission_cable, delay, period, log, until=SIM_TIME)
    assert log == expected
    received = [(t, what[1]) for t, who, what in expected if who == "receiver"]
    assert received and all(got == sent + delay for got, sent in received)
