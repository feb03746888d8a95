"""Mission-layer benchmark: the cost of a sim-time await, and of missions over action queues.

1. ``sleep``: T missions x W ``await sim.sleep(dt)`` calls in an empty simulation; reports wall
   time per wait (the driver's step is nearly free, so this is the mission machinery).
2. ``fleet``: N agents each looping move -> sleep -> move for S steps, once driven by missions
   (``await agent.move``) and once by synchronous action queues refilled from a callback;
   reports ms/step for both and the mission layer's overhead, best of ``--repeat`` interleaved
   runs (single runs on a small VM vary by +-10%).

Times are CPU seconds of the benchmark process (``time.process_time``), so other load on the
machine slows the figures less than it would wall-clock ones.

Run:  python benchmarks/async_bench.py [--tasks 1000] [--waits 1000] [--agents 1000] [--steps 600]
      [--repeat 3]
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import fleet_async as fa
from fleet_async import (
    Agent,
    AgentSpawnParams,
    MoveAction,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimulationParams,
    WaitAction,
)

BACKENDS = ("asyncio", "trio")
_clock = time.process_time
"""CPU time of this process: every mode is single-threaded and CPU bound, and on a shared
machine the wall clock also counts the time spent waiting for a core."""
WARMUP = 10
"""Untimed steps before the fleet measurements (as in benchmarks/fleet_bench.py)."""


def _params() -> SimulationParams:
    return SimulationParams(
        gui=False,
        monitor=False,
        target_rtf=0.0,
        timestep=0.1,
        enable_floor=False,
        collision_check_frequency=0,
    )


def sleep_bench(tasks: int, waits: int, backend: str) -> float:
    """Microseconds of wall time per ``await sim.sleep``."""
    with MultiRobotSimulationCore(_params()) as sim:

        async def sleeper() -> None:
            for _ in range(waits):
                await sim.sleep(0.1)

        async def main() -> None:
            async with sim.task_group() as tg:
                for _ in range(tasks):
                    tg.start_soon(sleeper)

        t0 = _clock()
        fa.run(sim, main, backend=backend)
        elapsed = _clock() - t0
    return elapsed / (tasks * waits) * 1e6


def simpy_bench(tasks: int, waits: int) -> float | None:
    """Microseconds per ``yield env.timeout(1)`` in SimPy (None without simpy)."""
    try:
        import simpy
    except ImportError:
        return None
    env = simpy.Environment()

    def sleeper() -> Any:
        for _ in range(waits):
            yield env.timeout(1)

    for _ in range(tasks):
        env.process(sleeper())
    t0 = _clock()
    env.run()
    return (_clock() - t0) / (tasks * waits) * 1e6


def _fleet(sim: MultiRobotSimulationCore, n: int) -> list[Agent]:
    cube = ShapeParams("box", half_extents=[0.05, 0.05, 0.05])
    return Agent.spawn_batch(
        [
            AgentSpawnParams(
                visual_shape=cube,
                collision_shape=cube,
                initial_pose=Pose.from_xyz(2.0 * i, 0.0, 0.1),
                controller={"type": "omni", "max_linear_vel": 2.0},
            )
            for i in range(n)
        ],
        sim,
    )


def fleet_missions(n: int, steps: int, backend: str, warmup: int = WARMUP) -> float:
    """ms/step with every agent driven by a mission, timed after ``warmup`` steps (so the
    missions' start is not charged to the steady state, as in :func:`fleet_queues`)."""
    with MultiRobotSimulationCore(_params()) as sim:
        agents = _fleet(sim, n)

        async def shuttle(agent: Agent) -> None:
            x = agent.get_pose().x
            while True:
                await agent.move(Pose.from_xyz(x, 1.0, 0.1))
                await sim.sleep(0.5)
                await agent.move(Pose.from_xyz(x, 0.0, 0.1))

        async def main() -> None:
            async with sim.task_group() as tg:
                for agent in agents:
                    tg.start_soon(shuttle, agent)

        started: list[float] = []

        def clock(step: int, **_: Any) -> None:
            if step == warmup:
                started.append(_clock())

        sim.events.on("post_step", clock)
        fa.run(sim, main, backend=backend, until=(warmup + steps) * sim.params.timestep)
        return (_clock() - started[0]) * 1e3 / steps


def fleet_queues(n: int, steps: int, warmup: int = WARMUP) -> float:
    """ms/step with the same work queued as actions, refilled when a sequence ends.

    The refill is event driven (on the completion of each sequence's last action), as a
    careful synchronous user would write it, so the baseline costs nothing per idle agent.
    """
    with MultiRobotSimulationCore(_params()) as sim:
        agents = _fleet(sim, n)
        last: dict[int, Any] = {}

        def queue(agent: Agent) -> None:
            x = agent.get_pose().x
            seq = [
                MoveAction(path=Pose.from_xyz(x, 1.0, 0.1)),
                WaitAction(duration=0.5),
                MoveAction(path=Pose.from_xyz(x, 0.0, 0.1)),
            ]
            last[agent.object_id] = seq[-1]
            agent.add_action_sequence(seq)

        def on_done(agent: Agent, action: Any) -> None:
            if last.get(agent.object_id) is action:
                queue(agent)

        sim.events.on("action_completed", on_done)
        for agent in agents:
            queue(agent)
        for _ in range(warmup):
            sim.step_once()
        t0 = _clock()
        for _ in range(steps):
            sim.step_once()
        return (_clock() - t0) * 1e3 / steps


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", type=int, default=1000)
    parser.add_argument("--waits", type=int, default=1000)
    parser.add_argument("--agents", type=int, default=1000)
    parser.add_argument("--steps", type=int, default=600)
    parser.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="fleet runs per mode, interleaved; the best of each is reported (default 3)",
    )
    args = parser.parse_args(argv)
    waits: dict[str, float] = {}
    for _ in range(max(1, args.repeat)):
        runs = {backend: sleep_bench(args.tasks, args.waits, backend) for backend in BACKENDS}
        simpy_us = simpy_bench(args.tasks, args.waits)
        if simpy_us is not None:
            runs["simpy"] = simpy_us
        for mode, us in runs.items():
            waits[mode] = min(us, waits.get(mode, us))
    for mode, us in waits.items():
        ratio = f" ({us / waits['simpy']:.2f}x SimPy)" if "simpy" in waits else ""
        print(
            f"sleep  {mode:<8} {args.tasks} tasks x {args.waits} waits: {us:6.2f} us per wait"
            f"{ratio} (best of {args.repeat})"
        )
    best: dict[str, float] = {}
    for _ in range(max(1, args.repeat)):
        runs = {"queues": fleet_queues(args.agents, args.steps)}
        for backend in ("asyncio", "trio"):
            runs[backend] = fleet_missions(args.agents, args.steps, backend)
        for mode, ms in runs.items():
            best[mode] = min(ms, best.get(mode, ms))
    queues = best["queues"]
    print(f"fleet  queues   {args.agents} agents: {queues:7.3f} ms/step (best of {args.repeat})")
    for backend in ("asyncio", "trio"):
        overhead = (best[backend] / queues - 1.0) * 100.0
        print(
            f"fleet  {backend:<8} {args.agents} agents: {best[backend]:7.3f} ms/step "
            f"({overhead:+.0f}% vs queues)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
