"""The realistic-fleet benchmark: what users switch on, not bare boxes.

Workload (N robots, seeded): box robots (0.6 x 0.4 x 0.2 m, omni, 1.5 m/s) on a grid 4 m
apart, each with a battery (``drain_per_meter`` 0.002, ``drain_per_second`` 0.0002,
``charge_rate`` 0.01, initial charge 0.5-1.0); a third patrol a 1.5 m square (``patrol``,
1 s wait at each corner), a third wander (``random_walk``, radius 1.5 m, waits 0.5-3 s), a
third run a mission each (move 1.5 m, charge 2-10 s, move home, wait 1-5 s, in a loop: no
mission waits more than 30 s); every other robot carries a tote (attached), one in ten has a
1 Hz per-object callback; ``sim.kpis()`` and collision checks every step are on. Spawned one
call at a time (``spawn_s``: through the first step), then run as missions
(``fleet_async.run``) for ``--seconds`` of sim time; ``step_ms`` is the wall time per
simulation step after a 5 s warm-up.

``benchmarks/seed_api_workloads.py realistic N`` is the same workload in the seed API's terms
(missions as action queues, no KPIs), which pybullet-fleet 0.8.0 also runs, for the ratio.
``reference=True`` runs every feature on its per-robot reference path (batteries stepped robot
by robot, controllers polled every step, callbacks scanned, attachments recomputed in full):
the trace must be the same to the bit (``tests/test_realistic_bench.py``).

Run:  fleet-async bench --realistic [--n 1000 10000] [--seconds 30] [--repeat R] [--json]
"""

from __future__ import annotations

import dataclasses
import gc
import math
import statistics
import sys
import time
from typing import Any, TextIO

import numpy as np

from fleet_async.bench import TIMESTEP, bench_params
from fleet_async.core.agents.agent import Agent
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.base.params import SimulationParams
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.simulation import MultiRobotSimulationCore
from fleet_async.core.world.shapes import ShapeParams

__all__ = ["WARMUP_S", "build", "run", "run_from_args", "set_reference_path", "trace"]

SEED = 42
WARMUP_S = 5.0
"""Sim seconds run before the timed span."""

_BODY = ShapeParams("box", half_extents=[0.3, 0.2, 0.1])
_TOTE = ShapeParams("box", half_extents=[0.15, 0.15, 0.1])


def params(kernels: str = "numpy") -> SimulationParams:
    """The workload's settings: the bare benchmark's (headless, unpaced, dt 0.1 s, checks
    every step), seeded; ``kernels`` as ``SimulationParams.kernels``."""
    return dataclasses.replace(bench_params(), seed=SEED, kernels=kernels)


def _on_tick(obj: Any, dt: float) -> None:
    """The 1 Hz per-object callback: reads the robot's state, as a monitor would."""
    obj.user_data["ticks"] = obj.user_data.get("ticks", 0) + 1


def build(sim: MultiRobotSimulationCore, n: int) -> list[tuple[Agent, Pose, Pose, list[float]]]:
    """Spawn the fleet one call at a time; return each mission robot with its two stops
    and its waits (seconds, drawn here so the run is the same on every path)."""
    side = math.ceil(math.sqrt(n))
    rng = np.random.default_rng(SEED)
    missions = []
    for i in range(n):
        x, y = 4.0 * (i % side), 4.0 * (i // side)
        controller: list[dict[str, Any]] = [
            {"type": "omni", "max_linear_vel": 1.5, "max_angular_vel": 2.0}
        ]
        role = i % 3
        if role == 0:
            square = [[x + 1.5, y, 0.1], [x + 1.5, y + 1.5, 0.1], [x, y + 1.5, 0.1], [x, y, 0.1]]
            controller.append({"type": "patrol", "waypoints": square, "wait": 1.0})
        elif role == 1:
            controller.append({"type": "random_walk", "radius": 1.5, "wait_range": [0.5, 3.0]})
        battery = {
            "initial_soc": 0.5 + 0.5 * float(rng.random()),
            "drain_per_meter": 0.002,
            "drain_per_second": 0.0002,
            "charge_rate": 0.01,
        }
        robot = Agent.from_params(
            AgentSpawnParams(
                visual_shape=_BODY,
                collision_shape=_BODY,
                initial_pose=Pose.from_xyz(x, y, 0.1),
                mass=0.0,
                controller=controller,
                plugins=[{"type": "battery", "config": battery}],
                name=f"robot_{i}",
            ),
            sim_core=sim,
        )
        if i % 2 == 0:
            tote = SimObject.from_mesh(_TOTE, _TOTE, Pose.from_xyz(x, y, 0.3), sim_core=sim)
            robot.attach_object(tote, relative_pose=Pose.from_xyz(0.0, 0.0, 0.2))
        if i % 10 == 0:
            robot.register_callback(_on_tick, frequency=1.0)
        if role == 2:
            waits = [w for _ in range(64) for w in (rng.uniform(2.0, 10.0), rng.uniform(1.0, 5.0))]
            missions.append(
                (robot, Pose.from_xyz(x, y, 0.1), Pose.from_xyz(x + 1.5, y, 0.1), waits)
            )
    return missions


def set_reference_path(sim: MultiRobotSimulationCore) -> None:
    """Run every feature on its per-robot reference path (see the module docstring)."""
    sim.fleet.reference_path = True
    sim.world.scan_callbacks = True
    sim.attachments.incremental = False


def _main(sim: MultiRobotSimulationCore, missions: list[Any]) -> Any:
    async def mission(robot: Agent, home: Pose, stop: Pose, waits: list[float]) -> None:
        for k in range(0, len(waits), 2):
            await robot.move(stop)
            await robot.charge(waits[k])
            await robot.move(home)
            await sim.sleep(waits[k + 1])

    async def main() -> None:
        async with sim.task_group() as tg:
            for robot, home, stop, waits in missions:
                tg.start_soon(mission, robot, home, stop, waits)

    return main


def run(
    n: int, seconds: float = 30.0, reference: bool = False, kernels: str = "numpy"
) -> dict[str, Any]:
    """Spawn, then run ``seconds`` of sim time; see the module docstring for the figures."""
    import fleet_async as fa  # the mission layer sits above core

    gc.collect()
    with MultiRobotSimulationCore(params(kernels)) as sim:
        t0 = time.perf_counter()
        missions = build(sim, n)
        sim.step_once()
        spawn_s = time.perf_counter() - t0
        if reference:
            set_reference_path(sim)
        kpis = sim.kpis(from_now=True)
        marks: dict[int, tuple[float, float]] = {}
        warm = round(WARMUP_S / TIMESTEP)

        def mark(step: int) -> None:
            marks.setdefault(step, (time.perf_counter(), time.process_time()))

        sim.add_step_observer(mark)
        gc.collect()
        t_run = (time.perf_counter(), time.process_time())
        fa.run(sim, _main(sim, missions), until=sim.sim_time + seconds)
        t_end = (time.perf_counter(), time.process_time())
        first = min((s for s in marks if s >= warm), default=None)
        steps = sim.step_count - (first if first is not None else 0)
        start = marks[first] if first is not None else t_run
        timed, timed_cpu = t_end[0] - start[0], t_end[1] - start[1]
        summary = kpis.summary()
    return {
        "n": n,
        "workload": "realistic",
        "spawn_s": spawn_s,
        "step_ms": timed * 1000.0 / max(steps, 1),
        "step_cpu_ms": timed_cpu * 1000.0 / max(steps, 1),
        "steps": steps,
        "reference": reference,
        "kernels": "numba" if sim.fleet.compiled else "numpy",
        "distance_total_m": summary.distance_total_m,
        "collisions": summary.collisions,
        "battery_min_soc": summary.battery_min_soc,
    }


def trace(n: int, seconds: float, reference: bool, kernels: str = "numpy") -> list[Any]:
    """Every step's poses, charges and KPIs of the workload, for the parity test."""
    import fleet_async as fa

    with MultiRobotSimulationCore(params(kernels)) as sim:
        missions = build(sim, n)
        sim.step_once()
        if reference:
            set_reference_path(sim)
        kpis = sim.kpis(from_now=True)
        agents = [robot for robot in sim.agents if isinstance(robot, Agent)]
        out: list[Any] = []

        def observe(step: int) -> None:
            store = sim.state
            out.append(
                (
                    step,
                    store.position[: store.high_water].tobytes(),
                    store.orientation[: store.high_water].tobytes(),
                    tuple(a.battery_soc for a in agents),
                    tuple(a.user_data.get("ticks", 0) for a in agents),
                )
            )

        sim.add_step_observer(observe)
        fa.run(sim, _main(sim, missions), until=sim.sim_time + seconds)
        out.append((kpis.summary(), kpis.per_robot(), sim.collision_count))
    return out


def run_from_args(args: Any, out: TextIO | None = None) -> int:
    """``fleet-async bench --realistic``: run each size ``--repeat`` times, report medians."""
    import json

    stream = out if out is not None else sys.stdout
    sizes = list(args.n) if args.n else [1000, 10000]
    for n in sizes:
        if n <= 0:
            raise ValueError(f"--n: fleet sizes must be > 0, got {n}")
    for n in sizes:
        runs = [run(n, args.seconds, kernels=args.kernels) for _ in range(max(1, args.repeat))]
        row = dict(runs[0])
        row["step_ms_runs"] = [r["step_ms"] for r in runs]
        row["step_ms"] = statistics.median(row["step_ms_runs"])
        row["spawn_s"] = statistics.median(r["spawn_s"] for r in runs)
        row["step_cpu_ms"] = statistics.median(r["step_cpu_ms"] for r in runs)
        if args.json:
            print(json.dumps(row), file=stream)
        else:
            print(
                f"N={n:>6} realistic: step {row['step_ms']:8.3f} ms "
                f"(CPU {row['step_cpu_ms']:.3f} ms)  "
                f"(runs {', '.join(f'{v:.3f}' for v in row['step_ms_runs'])}; "
                f"{row['steps']} steps timed, {row['kernels']})  spawn {row['spawn_s']:6.3f} s  "
                f"collisions {row['collisions']}",
                file=stream,
            )
        stream.flush()
    return 0
