"""Safety fields benchmark: the ``safety_fields`` phase's cost per step for a large fleet.

N box robots (0.6 x 0.4 m, omnidirectional, fields on) stand on a grid 1.5 m apart in rows;
each drives along its row to a goal 30 m away, so the robots of a row follow each other
(warning fields see the robot ahead, protective fields stop some) and the rows stay apart.
Reports the phase's mean time per step from the step profile (``safety_fields``), and the
whole step's, over ``--steps`` steps after a warm-up; collision checks are off, so the figure
is the fields' alone (they read the collision system's AABBs, refreshed by the phase itself).

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
            collision_check_frequency=0,
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


def measure(robots: int, steps: int, fields: bool) -> tuple[float, float]:
    """(mean safety_fields ms, mean step ms) per step."""
    sim, _ = build(robots, fields)
    with sim:
        for _ in range(WARMUP):
            sim.step_once()
        phase, total = [], []
        for _ in range(steps):
            timings = sim.step_once(return_profiling=True)
            assert timings is not None
            phase.append(timings.get("safety_fields", 0.0))
            total.append(timings["total"])
        stopped = len(sim.safety.stopped_agents())
        print(f"  fields={fields}: {stopped} robots stopped at the end")
    return statistics.median(phase), statistics.median(total)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=10_000)
    parser.add_argument("--steps", type=int, default=50)
    args = parser.parse_args()
    on_phase, on_total = measure(args.robots, args.steps, True)
    off_phase, off_total = measure(args.robots, args.steps, False)
    print(f"{args.robots} robots, median over {args.steps} steps (ms per step):")
    print(f"  fields on : safety_fields {on_phase:.3f}, step {on_total:.3f}")
    print(f"  fields off: safety_fields {off_phase:.3f}, step {off_total:.3f}")


if __name__ == "__main__":
    main()
