"""Bank renege (SimPy example ``bank_renege``): one counter, impatient customers.

Customers walk in at random, queue for the single counter and wait for it only as long as
their patience lasts: ``request | timeout(patience)``. Whoever reaches the counter in time is
served for a random while; the others renege. The interesting ties are a patience that runs
out in the very step the counter is handed on, and customers who walk in together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import simpy

import fleet_async as fa

SEED = 42
CUSTOMERS = 16
MEAN_GAP = 5.0  # mean time between two arrivals (s)
MEAN_SERVICE = 7.0  # mean time at the counter (s)
PATIENCE = (1.0, 4.0)  # a customer gives up after a uniform draw from this range (s)


@dataclass(frozen=True)
class Customer:
    name: str
    patience: float
    service: float
    gap: float  # until the next customer walks in


def customers(on_grid) -> list[Customer]:
    """Every customer's draws, made before any simulation runs."""
    rng = np.random.default_rng(SEED)
    return [
        Customer(
            name=f"customer{i:02d}",
            patience=on_grid(rng.uniform(*PATIENCE)),
            service=on_grid(rng.exponential(MEAN_SERVICE)),
            gap=on_grid(rng.exponential(MEAN_GAP), min_steps=0),
        )
        for i in range(CUSTOMERS)
    ]


def simpy_bank(crowd: list[Customer]) -> list[tuple]:
    env = simpy.Environment()
    counter = simpy.Resource(env, capacity=1)
    log: list[tuple] = []

    def visit(who: Customer):
        came = env.now
        log.append((env.now, who.name, "walks in"))
        with counter.request() as turn:
            got = yield turn | env.timeout(who.patience)
            if turn not in got:
                log.append((env.now, who.name, ("reneges after", env.now - came)))
                return
            log.append((env.now, who.name, ("at the counter after", env.now - came)))
            yield env.timeout(who.service)
            log.append((env.now, who.name, "served"))

    def door():
        for who in crowd:
            env.process(visit(who))
            yield env.timeout(who.gap)

    env.process(door())
    env.run()
    return log


async def mission_bank(sim, crowd: list[Customer], log: list[tuple]) -> None:
    counter = fa.Resource(sim, capacity=1)

    async def visit(who: Customer) -> None:
        came = sim.now
        log.append((sim.now, who.name, "walks in"))
        with counter.request() as turn:
            got = await (turn | sim.timeout(who.patience))
            if turn not in got:
                log.append((sim.now, who.name, ("reneges after", sim.now - came)))
                return
            log.append((sim.now, who.name, ("at the counter after", sim.now - came)))
            await sim.timeout(who.service)
            log.append((sim.now, who.name, "served"))

    for who in crowd:  # the main mission is the door
        sim.spawn(visit, who, name=who.name)
        await sim.timeout(who.gap)


def test_bank_renege_logs_match_simpy(on_grid, run_missions):
    crowd = customers(on_grid)
    expected = simpy_bank(crowd)
    log: list[tuple] = []
    run_missions(mission_bank, crowd, log)
    assert log == expected
    outcomes = [what[0] for _, _, what in expected if isinstance(what, tuple)]
    assert "reneges after" in outcomes and "at the counter after" in outcomes
