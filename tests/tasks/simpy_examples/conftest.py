"""SimPy's own documentation examples as the oracle for the mission kernel's event order.

Method. Each module here re-models one example of SimPy 4.1.2's documentation
(``docs/examples/code``) twice: once on SimPy itself (``simpy.Environment``, processes as
generators) and once as fleet_async missions. Both versions append the same events, as
``(sim time, who, what)`` tuples, to a list, and the test asserts that the two lists are equal,
entry for entry. SimPy's order rule is the reference: process starts and interrupts are URGENT,
everything else is NORMAL, and events due at the same time are processed in the order they
were scheduled.

Determinism. Nothing random happens while a simulation runs: every random quantity is drawn
before either simulation starts, per customer or machine, from a seeded
``numpy.random.Generator``, and every duration is rounded onto the step grid of a dyadic
timestep (``dt`` = 1, 0.5 or 0.25 s; ``on_grid``). Sums of grid values are exact binary
floats, so both versions see the very same durations and times tie exactly; a difference in
the logs can only come from the order in which the two kernels process events.

Coverage. Every test runs for each ``dt`` and on both anyio backends, and also asserts that
the contention its example is about (reneging, preemption, refuelling, ...) happened, so a
model tuned into a quiet corner cannot pass vacuously.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

import pytest

import fleet_async as fa


@pytest.fixture(params=[1.0, 0.5, 0.25], ids=lambda dt: f"dt={dt}")
def dt(request: pytest.FixtureRequest) -> float:
    """The simulation's timestep (s); dyadic, so grid times are exact floats."""
    return float(request.param)


@pytest.fixture(params=["asyncio", "trio"])
def backend(request: pytest.FixtureRequest) -> str:
    """The anyio backend the missions run on."""
    return str(request.param)


@pytest.fixture
def on_grid(dt: float) -> Callable[..., float]:
    """Round a duration onto the step grid: ``on_grid(seconds, min_steps=1)``.

    ``min_steps`` keeps a delay the model needs positive (a service time) at least that many
    steps long; pass 0 where a zero delay is part of the model (simultaneous arrivals).
    """

    def rounded(seconds: float, min_steps: int = 1) -> float:
        return max(round(seconds / dt), min_steps) * dt

    return rounded


@pytest.fixture
def run_missions(dt: float, backend: str) -> Callable[..., Any]:
    """Run ``model(sim, *args)`` as the main mission of a fresh headless simulation.

    ``run_missions(model, *args, until=None)`` returns what ``fa.run`` returns; each call gets
    its own simulation (timestep ``dt``, no floor), closed afterwards.
    """

    def run(model: Callable[..., Awaitable[Any]], *args: Any, until: float | None = None) -> Any:
        params = fa.SimulationParams(
            gui=False, monitor=False, target_rtf=0.0, timestep=dt, enable_floor=False
        )
        with fa.MultiRobotSimulationCore(params) as sim:
            return fa.run(sim, model, sim, *args, backend=backend, until=until)

    return run
