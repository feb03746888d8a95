"""Movie renege (SimPy example ``movie_renege``): one ticket counter, three sold-out events.

Moviegoers queue at a single counter for tickets to one of three movies. Each waits for either
her turn or her movie's *sold out* event, one shared event per movie: when a buyer leaves fewer
than two tickets, she triggers it and everybody still queued for that movie leaves at once.
Whoever reaches the counter wanting more tickets than are left argues a while, then leaves.
Arrivals come every half second on average, so with ``dt`` = 1 many walk in together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import simpy

import fleet_async as fa

SEED = 42
MOVIES = ("Python Unchained", "Kill Process", "Pulp Implementation")
TICKETS = 50  # per movie
SELLOUT_THRESHOLD = 2  # fewer tickets left than this: sold out
MEAN_GAP = 0.5  # mean time between arrivals (s)
ARGUING_TIME = 0.5  # s (a whole step when dt = 1)
SELLING_TIME = 1.0  # s
SIM_TIME = 120.0  # s
ARRIVALS_DRAWN = 1000  # more arrivals than SIM_TIME allows


@dataclass(frozen=True)
class Moviegoer:
    name: str
    gap: float  # waited before she arrives
    movie: str
    tickets: int


def moviegoers(on_grid) -> list[Moviegoer]:
    """Every arrival's draws, made before any simulation runs."""
    rng = np.random.default_rng(SEED)
    return [
        Moviegoer(
            name=f"moviegoer{i}",
            gap=on_grid(rng.exponential(MEAN_GAP), min_steps=0),
            movie=MOVIES[int(rng.integers(len(MOVIES)))],
            tickets=int(rng.integers(1, 7)),
        )
        for i in range(ARRIVALS_DRAWN)
    ]


def simpy_cinema(crowd: list[Moviegoer], arguing: float, selling: float) -> list[tuple]:
    env = simpy.Environment()
    counter = simpy.Resource(env, capacity=1)
    left = dict.fromkeys(MOVIES, TICKETS)
    sold_out = {movie: env.event() for movie in MOVIES}
    log: list[tuple] = []

    def queue_up(goer: Moviegoer):
        with counter.request() as turn:
            got = yield turn | sold_out[goer.movie]
            if turn not in got:
                log.append((env.now, goer.name, ("leaves: sold out", goer.movie)))
                return
            if left[goer.movie] < goer.tickets:
                yield env.timeout(arguing)
                log.append((env.now, goer.name, ("leaves after arguing", left[goer.movie])))
                return
            left[goer.movie] -= goer.tickets
            log.append((env.now, goer.name, ("buys", goer.movie, goer.tickets)))
            if left[goer.movie] < SELLOUT_THRESHOLD:
                sold_out[goer.movie].succeed()
                left[goer.movie] = 0
                log.append((env.now, "counter", ("sold out", goer.movie)))
            yield env.timeout(selling)

    def entrance():
        for goer in crowd:
            yield env.timeout(goer.gap)
            if left[goer.movie]:
                log.append((env.now, goer.name, ("queues for", goer.movie)))
                env.process(queue_up(goer))

    env.process(entrance())
    env.run(until=SIM_TIME)
    return log


async def mission_cinema(
    sim, crowd: list[Moviegoer], arguing: float, selling: float, log: list[tuple]
) -> None:
    counter = fa.Resource(sim, capacity=1)
    left = dict.fromkeys(MOVIES, TICKETS)
    sold_out = {movie: fa.Event(sim) for movie in MOVIES}

    async def queue_up(goer: Moviegoer) -> None:
        with counter.request() as turn:
            got = await (turn | sold_out[goer.movie])
            if turn not in got:
                log.append((sim.now, goer.name, ("leaves: sold out", goer.movie)))
                return
            if left[goer.movie] < goer.tickets:
                await sim.timeout(arguing)
                log.append((sim.now, goer.name, ("leaves after arguing", left[goer.movie])))
                return
            left[goer.movie] -= goer.tickets
            log.append((sim.now, goer.name, ("buys", goer.movie, goer.tickets)))
            if left[goer.movie] < SELLOUT_THRESHOLD:
                sold_out[goer.movie].succeed()
                left[goer.movie] = 0
                log.append((sim.now, "counter", ("sold out", goer.movie)))
            await sim.timeout(selling)

    for goer in crowd:  # the main mission is the entrance
        await sim.timeout(goer.gap)
        if left[goer.movie]:
            log.append((sim.now, goer.name, ("queues for", goer.movie)))
            sim.spawn(queue_up, goer, name=goer.name)


def test_movie_renege_logs_match_simpy(on_grid, run_missions):
    crowd, arguing, selling = moviegoers(on_grid), on_grid(ARGUING_TIME), on_grid(SELLING_TIME)
    expected = simpy_cinema(crowd, arguing, selling)
    log: list[tuple] = []
    run_missions(mission_cinema, crowd, arguing, selling, log, until=SIM_TIME)
    assert log == expected
    labels = [what[0] for _, _, what in expected]
    assert labels.count("sold out") == len(MOVIES)
    assert "leaves: sold out" in labels and "leaves after arguing" in labels
