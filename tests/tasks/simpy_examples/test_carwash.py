"""Carwash (SimPy example ``carwash``): cars queue for two washing machines.

Four cars are waiting at opening time and more keep coming. A car takes a free machine (or
waits for one), starts a separate washing process and waits for that process to end before it
drives off. The run stops at a fixed time with cars still queued and washing, which checks
that ``until`` stops both kernels before the events due at that very time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import simpy

import fleet_async as fa

SEED = 42
MACHINES = 2
WASH_TIME = 5.0  # s
EARLY_CARS = 4  # queued at opening time
CARS = 24  # all cars, early ones included (the last ones come after closing)
GAP = (1.0, 4.0)  # time between later arrivals: a uniform draw from this range (s)
CLOSING = 40.0  # the run stops here (s)


@dataclass(frozen=True)
class Car:
    name: str
    gap: float  # waited before this car arrives (0 for the early ones)
    dirt_removed: int  # percent


def cars(on_grid) -> list[Car]:
    """Every car's draws, made before any simulation runs."""
    rng = np.random.default_rng(SEED)
    return [
        Car(
            name=f"car{i}",
            gap=0.0 if i < EARLY_CARS else on_grid(rng.uniform(*GAP)),
            dirt_removed=int(rng.integers(50, 100)),
        )
        for i in range(CARS)
    ]


def simpy_carwash(queue: list[Car], wash_time: float) -> list[tuple]:
    env = simpy.Environment()
    machines = simpy.Resource(env, MACHINES)
    log: list[tuple] = []

    def wash(car: Car):
        yield env.timeout(wash_time)
        log.append((env.now, "carwash", ("cleaned", car.name, car.dirt_removed)))

    def visit(car: Car):
        log.append((env.now, car.name, "arrives"))
        with machines.request() as machine:
            yield machine
            log.append((env.now, car.name, "enters"))
            yield env.process(wash(car))
            log.append((env.now, car.name, "leaves"))

    def road():
        for car in queue:
            if car.gap:
                yield env.timeout(car.gap)
            env.process(visit(car))

    env.process(road())
    env.run(until=CLOSING)
    return log


async def mission_carwash(sim, queue: list[Car], wash_time: float, log: list[tuple]) -> None:
    machines = fa.Resource(sim, MACHINES)

    async def wash(car: Car) -> None:
        await sim.timeout(wash_time)
        log.append((sim.now, "carwash", ("cleaned", car.name, car.dirt_removed)))

    async def visit(car: Car) -> None:
        log.append((sim.now, car.name, "arrives"))
        with machines.request() as machine:
            await machine
            log.append((sim.now, car.name, "enters"))
            await sim.spawn(wash, car)  # waits for the washing process to end
            log.append((sim.now, car.name, "leaves"))

    for car in queue:  # the main mission is the road
        if car.gap:
            await sim.timeout(car.gap)
        sim.spawn(visit, car, name=car.name)


def test_carwash_logs_match_simpy(on_grid, run_missions):
    queue, wash_time = cars(on_grid), on_grid(WASH_TIME)
    expected = simpy_carwash(queue, wash_time)
    log: list[tuple] = []
    run_missions(mission_carwash, queue, wash_time, log, until=CLOSING)
    assert log == expected
    arrived = [who for _, who, what in expected if what == "arrives"]
    entered = [who for _, who, what in expected if what == "enters"]
    assert len(arrived) > len(entered) > MACHINES  # a queue formed and was still there at closing
