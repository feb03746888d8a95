"""Running a whole scenario: its missions, its queued actions, and when to stop.

``fleet-async run SCENARIO.yaml`` is :func:`run_scenario` with a progress bar and a summary, so
a script gets the same run with::

    sim = MultiRobotSimulationCore.from_yaml("examples/scenarios/warehouse.yaml")
    outcome = fleet_async.run_scenario(sim)

How long a run lasts:

- with a ``duration`` (the argument, else ``simulation.duration`` when > 0): exactly that long
  (the fewest whole steps covering it); missions still alive then are cancelled.
- without one: until the scenario's work is done, that is every mission of its ``missions:``
  section has returned and every agent has finished its queued actions (``actions:`` lists)
  and stopped (robots on a patrol or random-walk controller, whose work has no end, are not
  waited for); at most ``max_duration`` (600 s of sim time by default). A scenario with
  neither missions nor actions (robots on patrol controllers, say) has no end of its own and
  runs to ``max_duration``.

This module stands beside ``fleet_async.tasks`` and uses only its public ``run``: the core
describes the missions (``sim.scenario_missions``) and never imports the mission runtime.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

from fleet_async.core.agents.agent import Agent
from fleet_async.tasks import run

if TYPE_CHECKING:
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["DEFAULT_MAX_DURATION", "ScenarioOutcome", "run_scenario", "work_done"]

DEFAULT_MAX_DURATION = 600.0
"""Sim seconds a scenario without a duration may run before it is stopped."""


@dataclasses.dataclass(frozen=True)
class ScenarioOutcome:
    """How a :func:`run_scenario` run ended.

    Attributes:
        stopped: Why it stopped: ``"duration"`` (the duration was reached), ``"done"`` (its
            missions returned and its actions finished), ``"max_duration"`` (the cap of a run
            without a duration, whose work was not done) or ``"no_end"`` (the cap of a run
            without a duration, missions or actions: nothing it could finish).
        limit: The duration or cap that applied, in sim seconds.
        results: What each mission returned, by mission name (missions that did not return
            are absent).
    """

    stopped: str
    limit: float
    results: dict[str, Any]

    def describe(self) -> str:
        """One line for people: why the run stopped."""
        if self.stopped == "done":
            return "its work is done (missions returned, robots finished their actions)"
        if self.stopped == "duration":
            return f"the duration of {self.limit:g} s was reached"
        if self.stopped == "no_end":
            return (
                f"the scenario has no missions, no actions and no duration, so nothing to "
                f"finish: it ran the {self.limit:g} s cap (give a duration)"
            )
        return (
            f"the scenario sets no duration and its work was not done after {self.limit:g} s "
            "(the cap; give a duration to run longer)"
        )


def work_done(sim: MultiRobotSimulationCore) -> bool:
    """Whether every agent has an empty action queue and stands still, robots on a
    high-level controller (patrol, random walk: work without an end) aside."""
    return all(
        a.is_action_queue_empty() and (not a.is_moving or len(a.controllers) > 1)
        for a in _agents(sim)
    )


def _has_actions(sim: MultiRobotSimulationCore) -> bool:
    return any(not agent.is_action_queue_empty() for agent in _agents(sim))


def _agents(sim: MultiRobotSimulationCore) -> list[Agent]:
    return [agent for agent in sim.agents if isinstance(agent, Agent)]


def run_scenario(
    sim: MultiRobotSimulationCore,
    duration: float | None = None,
    *,
    max_duration: float = DEFAULT_MAX_DURATION,
    backend: str = "asyncio",
    watchdog: float = 30.0,
) -> ScenarioOutcome:
    """Run the scenario ``sim`` was built from: its missions and queued actions, in sim time.

    Args:
        sim: A simulation from ``MultiRobotSimulationCore.from_yaml`` / ``from_dict`` (any
            simulation works; one without missions just steps).
        duration: Sim seconds to run; None takes ``sim.params.duration`` when it is > 0,
            else runs until the work is done (see the module doc).
        max_duration: The cap of a run without a duration, in sim seconds.
        backend: The anyio host loop, "asyncio" or "trio".
        watchdog: Wall seconds a mission may hold the clock on a non-sim await.

    Returns:
        Why the run stopped, and what the missions returned.

    Raises:
        ValueError: for a duration or max_duration that is not > 0.
        BaseException: a mission's failure, as ``fleet_async.run`` raises it.
    """
    if duration is None and sim.params.duration > 0:
        duration = float(sim.params.duration)
    limit = duration if duration is not None else max_duration
    if not limit > 0:
        raise ValueError(f"run_scenario: the run length must be > 0 sim seconds, got {limit!r}")
    results: dict[str, Any] = {}
    finished: list[bool] = []
    specs = sim.scenario_missions
    ends_by_itself = duration is None and (bool(specs) or _has_actions(sim))

    async def scenario() -> None:
        async def mission(spec: Any) -> None:
            results[spec.name] = await spec.coroutine_function()(sim)

        if specs:
            async with sim.task_group() as group:
                for spec in specs:
                    group.start_soon(mission, spec, name=spec.name)
        if ends_by_itself:
            await sim.wait_until(lambda: work_done(sim))
            finished.append(True)
            return
        await sim.sleep_until(sim.sim_time + 2 * limit)  # past the end: `until` stops the run

    start = sim.sim_time
    run(sim, scenario, until=start + limit, then="cancel", backend=backend, watchdog=watchdog)
    if finished:
        stopped = "done"
    elif duration is not None:
        stopped = "duration"
    else:
        stopped = "max_duration" if ends_by_itself else "no_end"
    return ScenarioOutcome(stopped, limit, results)
