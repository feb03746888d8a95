"""Safety fields benchmark: the ``safety_fields`` phase's cost per step for a large fleet.

N box robots (0.6 x 0.4 m, omnidirectional, fields on) stand on a grid 1.5 m apart in rows;
each drives along its row to a goal 30 m away, so the robots of a row follow each other
(warning fields see the robot ahead, protective fields stop some) and the rows stay apart.
Reports the median over ``--steps`` steps (after a warm-up) of the step profile's
``safety_fields`` phase, of the ``collision_check`` phase (the collision system's own broad and
narrow phase on the same fleet, every step: a yardstick measured in the same run, so the ratio
holds on a loaded machine), and of the whole step. ``--only on`` / ``--only off`` runs one
configuration, for ``farm-bench`` to time whole processes side by side.

Phase times come from the step profile, in CPU time by default (its clock pointed at
``time.process_time``; ``--wall`` for wall time); "step CPU" is the process's CPU time per
step either way. Quote the median of
several runs (``farm-bench``) rather than one.

Run:  python benchmarks/safety_bench.py [--robots 10000] [--steps 50] [--wall]
      [--kernels numpy|auto|numba]
"""

from __future__ import annotations

import argparse
import statistics
import time

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimulationParams,
)
from fleet_async.core.base.compiled import KERNEL_MODES

BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.2])
WARMUP = 5


def build(
    robots: int, fields: bool, kernels: str = "numpy"
) -> tuple[MultiRobotSimulationCore, list[Agent]]:
    sim = MultiRobotSimulationCore(
        SimulationParams(
            gui=False,
            monitor=False,
            target_rtf=0.0,
            timestep=0.1,
            enable_floor=False,
            collision_check_frequency=None,
            kernels=kernels,
        )
    )
    per_row = 100
    params = [
        AgentSpawnParams(
            visual_shape=None,
            collision_shape=BOX,
            initial_pose=Pose.from_xyz(1.5 * (i % per_row), 1.5 * (i // per_row), 0.2),
            motion_mode="omnidirectional",
            safety_field=fields,
        )
        for i in range(robots)
    ]
    agents = Agent.spawn_batch(params, sim)
    for agent in agents:
        x, y, z = agent.get_pose().position.tolist()
        agent.set_path([Pose.from_xyz(x + 30.0, y, z)])
    return sim, agents


def measure(robots: int, steps: int, fields: bool, kernels: str) -> dict[str, float]:
    """Per-step medians (ms): the ``safety_fields`` phase, ``collision_check``, the step, the
    step's CPU time; and the phase's mean (the pair list's rebuilds are spikes)."""
    sim, _ = build(robots, fields, kernels)
    with sim:
        for _ in range(WARMUP):
            sim.step_once()
        phase, check, total, cpu = [], [], [], []
        for _ in range(steps):
            c0 = time.process_time()
            timings = sim.step_once(return_profiling=True)
            cpu.append((time.process_time() - c0) * 1e3)
            assert timings is not None
            phase.append(timings["safety_fields"])
            check.append(timings["collision_check"])
            total.append(timings["total"])
        stopped = len(sim.safety.stopped_agents())
        lists = sim.safety.pair_list_stats()
        print(f"  fields={fields}: {stopped} robots stopped at the end; pair list {lists}")
    return {
        "phase": statistics.median(phase),
        "phase_mean": statistics.fmean(phase),
        "check": statistics.median(check),
        "step": statistics.median(total),
        "cpu": statistics.median(cpu),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=10_000)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--only", choices=("on", "off"), default=None)
    parser.add_argument(
        "--kernels",
        choices=KERNEL_MODES,
        default="numpy",
        help="SimulationParams.kernels (default numpy, the simulation's default); numba "
        "kernels are compiled or loaded from their cache in the warm-up",
    )
    parser.add_argument(
        "--wall",
        action="store_true",
        help="phase times in wall time (default: the process's CPU time, steadier on a shared "
        "machine: the step profile's clock is pointed at time.process_time)",
    )
    args = parser.parse_args()
    if not args.wall:
        time.perf_counter = time.process_time  # the profile reads its clock at each step
    print(
        f"{args.robots} robots, kernels {args.kernels}, median over {args.steps} steps "
        "(ms per step):"
    )
    for fields in (True, False):
        if args.only is not None and fields != (args.only == "on"):
            continue
        m = measure(args.robots, args.steps, fields, args.kernels)
        print(
            f"  fields {'on ' if fields else 'off'}: safety_fields {m['phase']:.3f} "
            f"(mean {m['phase_mean']:.3f}), collision_check {m['check']:.3f}, "
            f"step {m['step']:.3f}, step CPU {m['cpu']:.3f}"
        )


if __name__ == "__main__":
    main()
