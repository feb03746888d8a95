"""Gas station refuelling (SimPy example ``gas_station_refuel``): pumps, a shared tank, a truck.

Cars take one of two pumps (a Resource), then draw the fuel they need from the station's
tank (a Container) and fill up at a fixed rate. A control process looks at the tank every ten
seconds and, below a threshold, calls the tank truck and waits for it; the truck arrives later
and tops the tank up. Cars arrive more often than in the example, so the tank runs dry: cars
wait at their pumps for the truck, and the cars behind them wait for a pump.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import simpy

import fleet_async as fa

SEED = 42
PUMPS = 2
STATION_TANK = 200  # litres
THRESHOLD = 25  # percent of a full tank: call the truck below this
CAR_TANK = 50  # litres
CAR_LEVEL = (5, 25)  # a car arrives with this many litres, drawn uniformly (integers)
REFUEL_SPEED = 2.0  # litres per second
TRUCK_TIME = 300.0  # s, from the call to the truck's arrival
CHECK_EVERY = 10.0  # s, between two looks at the tank
GAP = (5.0, 40.0)  # time between two arrivals: a uniform draw from this range (s)
SIM_TIME = 1000.0  # s
CARS_DRAWN = 250  # more cars than SIM_TIME lets arrive


@dataclass(frozen=True)
class Car:
    name: str
    gap: float  # waited before this car arrives
    litres: int  # what it needs to fill its tank
    refuel_time: float  # filling up that much at the pump (s)


def cars(on_grid) -> list[Car]:
    """Every car's draws, made before any simulation runs."""
    rng = np.random.default_rng(SEED)
    drawn = []
    for i in range(CARS_DRAWN):
        gap = on_grid(rng.uniform(*GAP))
        litres = CAR_TANK - int(rng.integers(CAR_LEVEL[0], CAR_LEVEL[1] + 1))
        drawn.append(Car(f"car{i}", gap, litres, on_grid(litres / REFUEL_SPEED)))
    return drawn


def simpy_station(traffic: list[Car], truck_time: float, check_every: float) -> list[tuple]:
    env = simpy.Environment()
    pumps = simpy.Resource(env, PUMPS)
    tank = simpy.Container(env, STATION_TANK, init=STATION_TANK)
    log: list[tuple] = []

    def fill_up(car: Car):
        log.append((env.now, car.name, "arrives"))
        with pumps.request() as pump:
            yield pump
            log.append((env.now, car.name, ("at a pump, tank has", tank.level)))
            yield tank.get(car.litres)
            yield env.timeout(car.refuel_time)
            log.append((env.now, car.name, ("leaves with", car.litres)))

    def truck():
        yield env.timeout(truck_time)
        delivered = tank.capacity - tank.level
        tank.put(delivered)
        log.append((env.now, "truck", ("delivers", delivered)))

    def control():
        while True:
            if tank.level * 100 < THRESHOLD * tank.capacity:
                log.append((env.now, "control", ("calls the truck, tank has", tank.level)))
                yield env.process(truck())
            yield env.timeout(check_every)

    def road():
        for car in traffic:
            yield env.timeout(car.gap)
            env.process(fill_up(car))

    env.process(control())
    env.process(road())
    env.run(until=SIM_TIME)
    return log


async def mission_station(
    sim, traffic: list[Car], truck_time: float, check_every: float, log: list[tuple]
) -> None:
    pumps = fa.Resource(sim, PUMPS)
    tank = fa.Container(sim, STATION_TANK, init=STATION_TANK)

    async def fill_up(car: Car) -> None:
        log.append((sim.now, car.name, "arrives"))
        with pumps.request() as pump:
            await pump
            log.append((sim.now, car.name, ("at a pump, tank has", tank.level)))
            await tank.get(car.litres)
            await sim.timeout(car.refuel_time)
            log.append((sim.now, car.name, ("leaves with", car.litres)))

    async def truck() -> None:
        await sim.timeout(truck_time)
        delivered = tank.capacity - tank.level
        tank.put(delivered)
        log.append((sim.now, "truck", ("delivers", delivered)))

    async def control() -> None:
        while True:
            if tank.level * 100 < THRESHOLD * tank.capacity:
                log.append((sim.now, "control", ("calls the truck, tank has", tank.level)))
                await sim.spawn(truck, name="truck")
            await sim.timeout(check_every)

    async def road() -> None:
        for car in traffic:
            await sim.timeout(car.gap)
            sim.spawn(fill_up, car, name=car.name)

    sim.spawn(control, name="control")
    sim.spawn(road, name="road")


def test_gas_station_logs_match_simpy(on_grid, run_missions):
    traffic, truck_time, check_every = cars(on_grid), on_grid(TRUCK_TIME), on_grid(CHECK_EVERY)
    expected = simpy_station(traffic, truck_time, check_every)
    log: list[tuple] = []
    run_missions(mission_station, traffic, truck_time, check_every, log, until=SIM_TIME)
    assert log == expected
    labels = [what[0] if isinstance(what, tuple) else what for _, _, what in expected]
    assert labels.count("delivers") >= 2
    dry = [what[1] for _, _, what in expected if what[0] == "at a pump, tank has"]
    assert min(dry) < CAR_TANK - CAR_LEVEL[1]  # some car had to wait for the truck
