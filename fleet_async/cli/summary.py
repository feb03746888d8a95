"""The summary that ``fleet-async run`` prints: what one run did, with its fleet KPIs."""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, cast

if TYPE_CHECKING:
    from fleet_async.core import FleetKpis
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.simulation import MultiRobotSimulationCore
    from fleet_async.scenario_runner import ScenarioOutcome

__all__ = ["RunSummary", "format_summary", "summarize"]


@dataclasses.dataclass(frozen=True)
class RunSummary:
    """What one run did.

    Attributes:
        robots: Agents in the simulation at the end, devices not included.
        objects: Sim objects at the end, robots included (as the monitor counts them).
        sim_time: Sim seconds at the end.
        steps: Steps this run took.
        wall_time: Wall seconds spent running (loading not included).
        actions_completed: The robots' ``ACTION_COMPLETED`` events during the run.
        actions_failed: The robots' ``ACTION_FAILED`` events (failed or cancelled actions).
        collisions: ``sim.collision_count`` at the end: contacts that began, that is how many
            times a pair of objects started touching.
        missions: The scenario's missions (its ``missions:`` entries).
        stopped: Why the run stopped, for people (empty when interrupted).
        recording: The saved recording, if any.
        trace: The saved trace, if any.
        interrupted: Whether Ctrl+C stopped the run early.
        kpis: The run's fleet KPIs (``sim.kpis().summary()``), shown after the collisions.
        devices: Agents in the simulation at the end that are devices (doors, lifts,
            workcells): not robots, so not in the fleet KPIs.
        safety_fields: Whether robots had safety fields (the summary then shows their stops,
            the time stopped and the deadlocks suspected).
    """

    robots: int
    objects: int
    sim_time: float
    steps: int
    wall_time: float
    actions_completed: int
    actions_failed: int
    collisions: int
    missions: int = 0
    stopped: str = ""
    recording: str | None = None
    interrupted: bool = False
    kpis: FleetKpis | None = None
    devices: int = 0
    trace: str | None = None
    safety_fields: bool = False

    @property
    def real_time_factor(self) -> float:
        """Sim seconds run per wall second (``inf`` if no wall time was measured)."""
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf


def format_summary(summary: RunSummary) -> str:
    """The summary as aligned ``name: value (what it counts)`` lines."""
    rtf = summary.real_time_factor
    kpis = summary.kpis
    robots = f"{summary.robots} (agents"
    if kpis is not None and kpis.robot_count != summary.robots:
        robots += (
            f" at the end; the figures below count {kpis.robot_count}, those removed during "
            "the run too"
        )
    if summary.devices:
        robots += f"; {summary.devices} more are devices, not robots"
    robots += ")"
    failed = "failed or cancelled"
    if kpis is not None and kpis.actions_cancelled:
        failed += f"; {kpis.actions_cancelled} of them cancelled"
    rows = [
        ("robots", robots),
        ("objects", f"{summary.objects} (every sim object, robots included)"),
        ("sim time", f"{summary.sim_time:.3f} s"),
        ("steps", str(summary.steps)),
        ("wall time", f"{summary.wall_time:.3f} s"),
        ("real-time factor", f"{rtf:.1f}x" if math.isfinite(rtf) else "inf"),
        ("missions", f"{summary.missions} (the scenario's missions: entries)"),
        ("actions completed", str(summary.actions_completed)),
        ("actions failed", f"{summary.actions_failed} ({failed})"),
        (
            "collisions",
            f"{summary.collisions} (contacts that began: each time two objects started to touch)",
        ),
        *(_kpi_rows(kpis) if kpis is not None else []),
        *(_safety_rows(kpis) if kpis is not None and summary.safety_fields else []),
    ]
    if summary.stopped:
        rows.append(("stopped", summary.stopped))
    if summary.recording is not None:
        rows.append(("recording", summary.recording))
    if summary.trace is not None:
        rows.append(("trace", summary.trace))
    if summary.interrupted:
        rows.append(("interrupted", "yes (Ctrl+C)"))
    return "\n".join(f"{name + ':':<19}{value}" for name, value in rows)


def _kpi_rows(kpis: FleetKpis) -> list[tuple[str, str]]:
    """The fleet KPIs the rows above do not show yet (docs/sweeps.md defines them)."""
    over = f"summed over {kpis.robot_count} robot{'' if kpis.robot_count == 1 else 's'}"

    def total(value: float, unit: str, mean: float, what: str = "") -> str:
        return f"{value:.1f} {unit} ({what}{over}; {mean:.1f} {unit} per robot)"

    if kpis.battery_used_total is None or kpis.battery_used_mean is None:
        battery = "- (no robot has a battery)"
    else:
        battery = (
            f"{kpis.battery_used_total:.3f} full batteries (summed over {kpis.battery_robots} "
            f"robot{'' if kpis.battery_robots == 1 else 's'} with one; "
            f"{kpis.battery_used_mean:.3f} per robot; lowest charge left "
            f"{kpis.battery_min_soc:.2f})"
        )
    return [
        ("tasks completed", f"{kpis.tasks_completed} (TASK_COMPLETED events: work reported done)"),
        ("tasks failed", f"{kpis.tasks_failed} (TASK_FAILED events)"),
        ("throughput", f"{kpis.throughput_per_hour:.1f} tasks completed per hour of sim time"),
        ("distance", total(kpis.distance_total_m, "m", kpis.distance_mean_m, "driven, ")),
        ("moving time", total(kpis.moving_time_total_s, "s", kpis.moving_time_mean_s)),
        (
            "waiting time",
            total(
                kpis.waiting_time_total_s,
                "s",
                kpis.waiting_time_mean_s,
                "standing with an action in progress, ",
            ),
        ),
        (
            "idle time",
            total(kpis.idle_time_total_s, "s", kpis.idle_time_mean_s, "standing with no action, "),
        ),
        ("mission errors", f"{kpis.mission_errors} (exceptions that ended a mission)"),
        ("battery used", battery),
    ]


def _safety_rows(kpis: FleetKpis) -> list[tuple[str, str]]:
    """What the robots' safety fields cost: stops, time stopped, deadlocks suspected."""
    n = kpis.robot_count
    mean = kpis.safety_stopped_time_total_s / n if n else 0.0
    return [
        (
            "safety stops",
            f"{kpis.safety_stops} (a protective field stopped a robot; "
            f"{kpis.safety_stopped_time_total_s:.1f} s stopped, summed over {n} "
            f"robot{'' if n == 1 else 's'}; {mean:.1f} s per robot)",
        ),
        (
            "deadlocks",
            f"{kpis.deadlocks_suspected} suspected (robots held by each other's fields: "
            "deadlock_suspected events)",
        ),
    ]


def summarize(
    sim: MultiRobotSimulationCore,
    row: FleetKpis,
    steps: int,
    wall: float,
    outcome: ScenarioOutcome | None,
    recording: str | None,
    trace: str | None = None,
) -> RunSummary:
    """The summary of a run of ``steps`` steps in ``wall`` seconds that ended with ``outcome``
    (None: interrupted), from the run's fleet KPIs ``row``."""
    devices = sum(1 for agent in sim.agents if not cast("Agent", agent).is_robot)
    return RunSummary(
        robots=sim.world.agent_count - devices,  # the monitor's agents are these and devices
        objects=sim.world.object_count,
        sim_time=sim.sim_time,
        steps=steps,
        wall_time=wall,
        actions_completed=row.actions_completed,
        actions_failed=row.actions_failed,
        collisions=sim.collision_count,
        missions=len(sim.scenario_missions),
        stopped=outcome.describe() if outcome is not None else "",
        recording=recording,
        trace=trace,
        interrupted=outcome is None,
        kpis=row,
        devices=devices,
        safety_fields=sim.safety.enabled or row.safety_stops > 0,
    )
