"""Safety fields benchmark: the ``safety_fields`` phase's cost per step for a large fleet.

N box robots (0.6 x 0.4 m, omnidirectional, fields on) stand on a grid 1.5 m apart in rows;
each drives along its row to a goal 30 m away, so the robots of a row follow each other
(warning fields see the robot ahead, protective fields stop some) and the rows stay apart.
Reports the median over ``--steps`` steps (after a warm-up) of the step profile's
``safety_fields`` phase, of the ``collision_check`` phase (the collision system's own broad and
narrow phase on the same fleet, every step: a yardstick measured in the same run, so the ratio
holds on a loaded machine), and of the whole step. ``--only on`` / ``--only off`` runs one
configuration, for ``farm-bench`` to time whole processes side by side.

Times are CPU-bound single-thread wall times of this process; the machine may be loaded, so
quote the median of several runs (``farm-bench``) rather than one.

Run:  python benchmarks/safety_bench.py [--robots 10000] [--steps 50]
"""

from __future__ import annotations

import argparse
import statistics

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimulationParams,
)

BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.2])
WARMUP = 5


def build(robots: int, fields: bool) -> tuple[MultiRobotSimulationCore, list[Agent]]:
    sim = MultiRobotSimulationCore(
        SimulationParams(
            gui=False,
            monitor=False,
            target_rtf=0.0,
            timestep=0.1,
            enable_floor=False,
            collision_check_frequency=None,
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


def measure(robots: int, steps: int, fields: bool) -> tuple[float, float, float]:
    """Median (safety_fields ms, collision_check ms, step ms) per step."""
    sim, _ = build(robots, fields)
    with sim:
        for _ in range(WARMUP):
            sim.step_once()
        phase, check, total = [], [], []
        for _ in range(steps):
            timings = sim.step_once(return_profiling=True)
            assert timings is not None
            phase.append(timings["safety_fields"])
            check.append(timings["collision_check"])
            total.append(timings["total"])
        stopped = len(sim.safety.stopped_agents())
        print(f"  fields={fields}: {stopped} robots stopped at the end")
    return statistics.median(phase), statistics.median(check), statistics.median(total)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=10_000)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--only", choices=("on", "off"), default=None)
    args = parser.parse_args()
    print(f"{args.robots} robots, median over {args.steps} steps (ms per step):")
    for fields in (True, False):
        if args.only is not None and fields != (args.only == "on"):
            continue
        phase, check, total = measure(args.robots, args.steps, fields)
        print(
            f"  fields {'on ' if fields else 'off'}: safety_fields {phase:.3f}, "
            f"collision_check {check:.3f}, step {total:.3f}"
        )


if __name__ == "__main__":
    main()
