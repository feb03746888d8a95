"""What each built-in feature costs a fleet that barely moves: the issue-28 review's cases.

One process per case (``--case``), N robots (0.6 x 0.4 m boxes, omni, 4 m apart), timed over
``--steps`` calls of ``step_once()`` after a warm-up, printed as one JSON line (``step_ms``
wall, ``step_cpu_ms`` CPU, ``idle_steps``: what ``sim.idle_steps(1000)`` answers after the
timed steps, 0 when something blocks skipping):

- ``battery``: every robot with a battery, the fleet idle;
- ``patrol``: every robot patrolling two points with a 600 s wait (so, waiting);
- ``callbacks``: every robot with a per-object callback at 0.25 Hz;
- ``carriers``: every robot carrying a tote, the fleet idle;
- ``kpis``: ``sim.kpis()`` on, the fleet idle;
- ``all``: all of the above at once;
- ``one_mover``: 1 of N robots driving, nothing else (the broad phase's sparse case).

Run before and after a change (or on two trees) with the same arguments, e.g.
``PYTHONPATH=. python benchmarks/feature_bench.py --case battery --n 1000``.
"""

from __future__ import annotations

import argparse
import json
import math
import time

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimObject,
    SimulationParams,
)

CASES = ("battery", "patrol", "callbacks", "carriers", "kpis", "all", "one_mover")


def _fleet(sim: MultiRobotSimulationCore, n: int, case: str) -> list[Agent]:
    body = ShapeParams("box", half_extents=[0.3, 0.2, 0.1])
    tote = ShapeParams("box", half_extents=[0.15, 0.15, 0.1])
    side = math.ceil(math.sqrt(n))
    every = case == "all"
    agents = []
    for i in range(n):
        x, y = 4.0 * (i % side), 4.0 * (i // side)
        controller: list[dict] = [{"type": "omni", "max_linear_vel": 1.5}]
        if case == "patrol" or every:
            patrol = {"type": "patrol", "waypoints": [[x, y, 0.1], [x + 1, y, 0.1]], "wait": 600}
            controller.append(patrol)
        plugins = [{"type": "battery"}] if case == "battery" or every else None
        agent = Agent.from_params(
            AgentSpawnParams(
                visual_shape=body,
                collision_shape=body,
                initial_pose=Pose.from_xyz(x, y, 0.1),
                controller=controller,
                plugins=plugins,
            ),
            sim_core=sim,
        )
        if case == "carriers" or every:
            box = SimObject.from_mesh(tote, tote, Pose.from_xyz(x, y, 0.3), sim_core=sim)
            agent.attach_object(box, relative_pose=Pose.from_xyz(0.0, 0.0, 0.2))
        if case == "callbacks" or every:
            agent.register_callback(lambda obj, dt: None, frequency=0.25)
        agents.append(agent)
    return agents


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: one case, one JSON line."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--case", choices=CASES, required=True)
    parser.add_argument("--n", type=int, default=1000)
    parser.add_argument("--steps", type=int, default=300)
    args = parser.parse_args(argv)
    params = SimulationParams(
        gui=False, monitor=False, target_rtf=0.0, timestep=0.1, enable_floor=False, seed=0
    )
    with MultiRobotSimulationCore(params) as sim:
        agents = _fleet(sim, args.n, args.case)
        if args.case in ("kpis", "all"):
            sim.kpis()
        if args.case == "one_mover":
            agents[args.n // 2].set_goal_pose(Pose.from_xyz(1e4, 0.0, 0.1))
        for _ in range(20):  # patrols reach their first point and start waiting
            sim.step_once()
        t0, c0 = time.perf_counter(), time.process_time()
        for _ in range(args.steps):
            sim.step_once()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        row = {
            "case": args.case,
            "n": args.n,
            "step_ms": wall * 1e3 / args.steps,
            "step_cpu_ms": cpu * 1e3 / args.steps,
            "idle_steps": sim.idle_steps(1000),
        }
    print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
