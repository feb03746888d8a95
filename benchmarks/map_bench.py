"""Grid map benchmark: the MovingAI warehouse map warehouse-10-20-10-2-1 (161 x 63 cells of 1 m)
with 1,000 robots with safety fields driving along its aisles.

The map is the benchmark set's own (``tests/data/traffic/warehouse-10-20-10-2-1.map``, see the
README there): shelf blocks 10 cells long and 2 deep, one-cell aisles between the shelf rows,
one-cell gaps between the blocks, an open area on each side. The robots (0.6 x 0.4 m boxes,
omnidirectional, fields on: 1 m/s, so the warning field reaches 1.1 m ahead) start on random
cells of the long east-west aisles and drive one way per aisle (alternate aisles east and west,
as one-way aisles are run), each to a cell 20-60 m further along its aisle: robots catch up
with slower ones ahead, slow in their warning fields and stop behind each other, and the map's
shelves stand beside every field. ``--flow head-on`` instead sends half the robots of each
aisle the other way (a stress test: they block each other for good).

Reports the wall time to load the map, and with the robots spawned, and the median step (with
the ``safety_fields`` and ``collision_check`` phases, collisions checked every step) over
``--steps`` steps, from the step profile: in CPU time by default (``time.process_time``, what
the run costs, steadier on a shared machine), in wall time with ``--wall``.

Run:  python benchmarks/map_bench.py [--robots 1000] [--steps 50] [--flow one-way|head-on] [--wall]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimulationParams,
)

MAP = Path(__file__).resolve().parents[1] / "tests/data/traffic/warehouse-10-20-10-2-1.map"
BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.2])
WARMUP = 5


def aisle_cells(free: np.ndarray, width: int) -> np.ndarray:
    """(K, 2) (row, col) free cells of the rows that are free from one side to the other
    (the long aisles), without the map's border columns."""
    rows, counts = np.unique(free[:, 0], return_counts=True)
    long_rows = rows[counts >= width - 2]
    cells = free[np.isin(free[:, 0], long_rows)]
    return cells[(cells[:, 1] >= 1) & (cells[:, 1] <= width - 2)]


def build(robots: int, flow: str, seed: int = 0) -> tuple[MultiRobotSimulationCore, float, float]:
    """The simulation with map and robots on their way; (sim, map load s, load + spawn s)."""
    t0 = time.monotonic()
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
    loaded = sim.load_map(MAP, resolution=1.0)
    t_map = time.monotonic() - t0
    width = loaded.grid.occupied.shape[1]
    cells = aisle_cells(loaded.free_cells(), width)
    rng = np.random.default_rng(seed)
    starts = cells[rng.choice(len(cells), size=robots, replace=False)]
    params = [
        AgentSpawnParams(
            visual_shape=None,
            collision_shape=BOX,
            initial_pose=Pose.from_xyz(*loaded.cell_position(int(r), int(c), 0.2)),
            motion_mode="omnidirectional",
            safety_field=True,
        )
        for r, c in starts.tolist()
    ]
    agents = Agent.spawn_batch(params, sim)
    t_load = time.monotonic() - t0
    aisles = np.unique(cells[:, 0])
    for k, (agent, (r, c)) in enumerate(zip(agents, starts.tolist(), strict=True)):
        east = int(np.searchsorted(aisles, r)) % 2 == 0
        if flow == "head-on" and k % 2:
            east = not east
        step = int(rng.integers(20, 61))
        goal = min(c + step, width - 2) if east else max(c - step, 1)
        if goal == c:
            goal = c - 1 if east else c + 1
        agent.set_path([Pose.from_xyz(*loaded.cell_position(int(r), int(goal), 0.2))])
    return sim, t_map, t_load


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=1000)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--flow", choices=("one-way", "head-on"), default="one-way")
    parser.add_argument(
        "--wall",
        action="store_true",
        help="phase times in wall time (default: the process's CPU time, steadier on a shared "
        "machine: the step profile's clock is pointed at time.process_time)",
    )
    args = parser.parse_args()
    if not args.wall:
        time.perf_counter = time.process_time  # the profile reads its clock at each step
    sim, t_map, t_load = build(args.robots, args.flow)
    loaded = sim.maps[0]
    with sim:
        for _ in range(WARMUP):
            sim.step_once()
        steps, phase, check, cpu = [], [], [], []
        for _ in range(args.steps):
            c0 = time.process_time()
            timings = sim.step_once(return_profiling=True)
            cpu.append((time.process_time() - c0) * 1e3)
            assert timings is not None
            steps.append(timings["total"])
            phase.append(timings["safety_fields"])
            check.append(timings["collision_check"])
        stopped = len(sim.safety.stopped_agents())
        lists = sim.safety.pair_list_stats()
    print(
        f"{MAP.name}: {len(loaded.lo)} obstacle boxes in {len(loaded.bodies)} bodies, loaded "
        f"in {t_map:.2f} s; with {args.robots} robots spawned: {t_load:.2f} s"
    )
    print(
        f"step (median of {args.steps}, flow {args.flow}): {statistics.median(steps):.2f} ms "
        f"(CPU {statistics.median(cpu):.2f} ms), of which safety_fields "
        f"{statistics.median(phase):.2f} ms, collision_check {statistics.median(check):.2f} ms; "
        f"{stopped} robots stopped at the end; pair list {lists}"
    )


if __name__ == "__main__":
    main()
