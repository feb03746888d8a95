"""Machine shop (SimPy example ``machine_shop``): breakdowns, one repairman, preemption.

Each machine makes parts one after another and breaks down now and then (a separate breaker
process interrupts it). A broken machine calls the single repairman, whose requests are
preemptive: a repair outranks the repairman's own low-priority jobs, which are interrupted
(``Preempted`` cause) and resumed later with the time they still need. Machines that break
while the repairman is busy repairing another one queue for him, and a machine can break in
the very step its part is done (the URGENT interrupt comes before the due timeout). Both
versions also log who preempted whom and the preempted usage's start time, so ``Preempted``
is compared too.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import simpy

import fleet_async as fa

SEED = 40
MACHINES = 3
PART_TIME = (10.0, 2.0)  # mean and sigma of the time to make one part (s)
MEAN_TIME_TO_FAILURE = 120.0  # s (shrunk from the example's 300: a short run breaks often)
REPAIR_TIME = 20.0  # s
JOB_TIME = 20.0  # one of the repairman's own jobs (s)
SIM_TIME = 600.0  # s
PARTS_DRAWN = 150  # more than a machine can make in SIM_TIME
FAILURES_DRAWN = 80  # more breakdowns than a machine can have in SIM_TIME


@dataclass(frozen=True)
class Machine:
    name: str
    part_times: tuple[float, ...]
    times_to_failure: tuple[float, ...]


def machines(on_grid) -> list[Machine]:
    """Every machine's draws, made before any simulation runs."""
    rng = np.random.default_rng(SEED)
    return [
        Machine(
            name=f"machine{i}",
            part_times=tuple(on_grid(t) for t in rng.normal(*PART_TIME, PARTS_DRAWN)),
            times_to_failure=tuple(
                on_grid(t) for t in rng.exponential(MEAN_TIME_TO_FAILURE, FAILURES_DRAWN)
            ),
        )
        for i in range(MACHINES)
    ]


def simpy_shop(shop: list[Machine], repair_time: float, job_time: float) -> list[tuple]:
    env = simpy.Environment()
    repairman = simpy.PreemptiveResource(env, capacity=1)
    log: list[tuple] = []
    broken: dict[str, bool] = {}
    names: dict[object, str] = {}  # process -> name, to log who preempted

    def produce(machine: Machine):
        for made, part_time in enumerate(machine.part_times, start=1):
            left = part_time
            while left:
                began = env.now
                try:
                    yield env.timeout(left)
                    left = 0
                except simpy.Interrupt:
                    broken[machine.name] = True
                    left -= env.now - began
                    log.append((env.now, machine.name, ("breaks down", left)))
                    with repairman.request(priority=1) as repair:
                        yield repair
                        log.append((env.now, machine.name, "repair starts"))
                        yield env.timeout(repair_time)
                    broken[machine.name] = False
                    log.append((env.now, machine.name, "repaired"))
            log.append((env.now, machine.name, ("part done", made)))

    def breaker(machine: Machine, production: simpy.Process):
        for delay in machine.times_to_failure:
            yield env.timeout(delay)
            if not broken[machine.name]:
                production.interrupt()

    def own_jobs():
        for job in itertools.count(1):
            left = job_time
            while left:
                began = None  # stays None if preempted before the grant resumed us
                with repairman.request(priority=2) as slot:
                    try:
                        yield slot
                        began = env.now
                        log.append((env.now, "repairman", ("works on job", job, left)))
                        yield env.timeout(left)
                        left = 0
                    except simpy.Interrupt as stop:
                        if began is not None:
                            left -= env.now - began
                        by, since = names[stop.cause.by], stop.cause.usage_since
                        log.append((env.now, "repairman", ("preempted by", by, since)))
            log.append((env.now, "repairman", ("job done", job)))

    for machine in shop:
        broken[machine.name] = False
        production = env.process(produce(machine))
        names[production] = machine.name
        env.process(breaker(machine, production))
    env.process(own_jobs())
    env.run(until=SIM_TIME)
    return log


async def mission_shop(
    sim, shop: list[Machine], repair_time: float, job_time: float, log: list[tuple]
) -> None:
    repairman = fa.PreemptiveResource(sim, capacity=1)
    broken: dict[str, bool] = {}
    names: dict[object, str] = {}  # mission -> name, to log who preempted

    async def produce(machine: Machine) -> None:
        for made, part_time in enumerate(machine.part_times, start=1):
            left = part_time
            while left:
                began = sim.now
                try:
                    await sim.timeout(left)
                    left = 0
                except fa.Interrupt:
                    broken[machine.name] = True
                    left -= sim.now - began
                    log.append((sim.now, machine.name, ("breaks down", left)))
                    with repairman.request(priority=1) as repair:
                        await repair
                        log.append((sim.now, machine.name, "repair starts"))
                        await sim.timeout(repair_time)
                    broken[machine.name] = False
                    log.append((sim.now, machine.name, "repaired"))
            log.append((sim.now, machine.name, ("part done", made)))

    async def breaker(machine: Machine, production: fa.Mission) -> None:
        for delay in machine.times_to_failure:
            await sim.timeout(delay)
            if not broken[machine.name]:
                production.interrupt()

    async def own_jobs() -> None:
        for job in itertools.count(1):
            left = job_time
            while left:
                began = None  # stays None if preempted before the grant resumed us
                with repairman.request(priority=2) as slot:
                    try:
                        await slot
                        began = sim.now
                        log.append((sim.now, "repairman", ("works on job", job, left)))
                        await sim.timeout(left)
                        left = 0
                    except fa.Interrupt as stop:
                        if began is not None:
                            left -= sim.now - began
                        by, since = names[stop.cause.by], stop.cause.usage_since
                        log.append((sim.now, "repairman", ("preempted by", by, since)))
            log.append((sim.now, "repairman", ("job done", job)))

    for machine in shop:
        broken[machine.name] = False
        production = sim.spawn(produce, machine, name=machine.name)
        names[production] = machine.name
        sim.spawn(breaker, machine, production, name=f"{machine.name} breaker")
    sim.spawn(own_jobs, name="repairman")


def test_machine_shop_logs_match_simpy(on_grid, run_missions):
    shop, repair_time, job_time = machines(on_grid), on_grid(REPAIR_TIME), on_grid(JOB_TIME)
    expected = simpy_shop(shop, repair_time, job_time)
    log: list[tuple] = []
    run_missions(mission_shop, shop, repair_time, job_time, log, until=SIM_TIME)
    assert log == expected
    labels = [what[0] if isinstance(what, tuple) else what for _, _, what in expected]
    assert {"breaks down", "preempted by", "job done", "part done"} <= set(labels)
    assert queued_for_repair(expected)
    assert (  # a breakdown in the very step a part is done: the interrupt comes first
        "breaks down",
        0.0,
    ) in [what for _, _, what in expected]


def queued_for_repair(log: list[tuple]) -> bool:
    """Whether some machine broke down while the repairman was repairing another one."""
    broke_at: dict[str, float] = {}
    for t, who, what in log:
        if isinstance(what, tuple) and what[0] == "breaks down":
            broke_at[who] = t
        elif what == "repair starts" and t > broke_at[who]:
            return True
    return False
