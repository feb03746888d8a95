"""Actions that end in one step resume their missions as one run of STEP events
(``kernel.EventRun``); what those missions schedule meanwhile must still come in its place.

The order is the rule's (docs/missions.md): at one step URGENT events (starts, interrupts,
cancel deliveries) come before STEP ones, so a mission started or interrupted by the first
mission resumed from a step's outcomes runs before the next outcome resumes its mission.
"""

from __future__ import annotations

import pytest

import fleet_async as fa
from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimulationParams

BACKENDS = ["asyncio", "trio"]


def _fleet(n: int) -> tuple[MultiRobotSimulationCore, list[Agent]]:
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, monitor=False, target_rtf=0.0, timestep=0.1, seed=0)
    )
    box = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
    robots = [
        Agent.from_mesh(box, box, Pose.from_xyz(2.0 * i, 0, 0.1), sim_core=sim, controller="omni")
        for i in range(n)
    ]
    return sim, robots


def _trace(backend: str) -> list[tuple[str, int]]:
    sim, (a, b, c, d) = _fleet(4)
    log: list[tuple[str, int]] = []
    missions: dict[str, fa.Mission] = {}

    async def started() -> None:
        log.append(("started", sim.step_count))
        await sim.sleep(0)
        log.append(("started slept 0", sim.step_count))

    async def first() -> None:
        await a.wait(1.0)
        log.append(("a", sim.step_count))
        sim.spawn(started)  # URGENT: before b's and c's outcomes
        missions["c"].interrupt("from a")  # URGENT: c hears it before its own outcome
        missions["d"].cancel()  # a cancel delivery (URGENT) too

    async def second() -> None:
        await b.wait(1.0)
        log.append(("b", sim.step_count))

    async def third() -> None:
        try:
            await c.wait(1.0)
            log.append(("c", sim.step_count))
        except fa.Interrupt as interrupt:
            log.append((f"c interrupted {interrupt.cause}", sim.step_count))
            done = await c.wait(0.5)  # the ended wait no longer resumes it; a new one does
            log.append((f"c {done.status.value}", sim.step_count))

    async def fourth() -> None:
        try:
            await d.wait(1.0)
            log.append(("d", sim.step_count))
        finally:
            log.append(("d ends", sim.step_count))

    async def main() -> None:
        async with sim.task_group() as tg:
            for name, fn in (("a", first), ("b", second), ("c", third), ("d", fourth)):
                missions[name] = tg.start_soon(fn, name=name)

    try:
        fa.run(sim, main, backend=backend)
    finally:
        sim.close()
    return log


@pytest.mark.parametrize("backend", BACKENDS)
def test_urgent_events_scheduled_by_an_outcome_come_before_the_next_outcome(
    backend: str,
) -> None:
    # The four waits end at the end of step 10, in agent order a, b, c, d. a's mission runs
    # first and schedules a start, an interrupt of c and a cancellation of d: all three are
    # URGENT and come before b's outcome; c's and d's outcomes then resume nobody.
    assert _trace(backend) == [
        ("a", 10),
        ("started", 10),
        ("c interrupted from a", 10),
        ("d ends", 10),
        ("b", 10),
        ("started slept 0", 10),
        ("c completed", 15),
    ]
