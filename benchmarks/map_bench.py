"""Grid map benchmark: load a 161 x 63 warehouse-like MovingAI map with 1,000 robots, then step
them with safety fields on.

The map is generated here in MovingAI's format (not the benchmark set's
warehouse-10-20-10-2-1, whose licence we have not checked): a 161 x 63 grid with a free border
of 2 cells, shelf blocks 10 cells long and 1 deep in rows 2 cells apart, 2-cell cross aisles
every 12 cells (the same dimensions as the warehouse maps of the MovingAI set). Robots (0.6 x
0.4 m, cells of 1 m) start on free cells and each drives to another free cell in its aisle.

Reports the wall time to load the map and spawn the robots, and the median step time (with the
``safety_fields`` and ``collision_check`` phases' shares) over ``--steps`` steps.

Run:  python benchmarks/map_bench.py [--robots 1000] [--steps 50]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
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

WIDTH, HEIGHT = 161, 63
BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.2])


def warehouse_text() -> str:
    """The generated map, in MovingAI's .map format."""
    rows = []
    for y in range(HEIGHT):
        row = []
        for x in range(WIDTH):
            inner = 2 <= x < WIDTH - 2 and 2 <= y < HEIGHT - 2
            shelf = inner and y % 2 == 0 and (x - 2) % 12 < 10
            row.append("@" if shelf else ".")
        rows.append("".join(row))
    return f"type octile\nheight {HEIGHT}\nwidth {WIDTH}\nmap\n" + "\n".join(rows) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=1000)
    parser.add_argument("--steps", type=int, default=50)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "warehouse-161x63.map"
        path.write_text(warehouse_text())
        t0 = time.perf_counter()
        sim = MultiRobotSimulationCore(
            SimulationParams(gui=False, monitor=False, target_rtf=0.0, enable_floor=False)
        )
        loaded = sim.load_map(path, resolution=1.0)
        t_map = time.perf_counter() - t0
        free = loaded.free_cells()
        aisle = free[(free[:, 0] % 2 == 1) & (free[:, 0] >= 3) & (free[:, 0] < HEIGHT - 3)]
        rng = np.random.default_rng(0)
        starts = aisle[rng.choice(len(aisle), size=args.robots, replace=False)]
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
        t_load = time.perf_counter() - t0
        for agent, (r, c) in zip(agents, starts.tolist(), strict=True):
            goal_col = int(rng.integers(2, WIDTH - 2))
            agent.set_path([Pose.from_xyz(*loaded.cell_position(int(r), goal_col, 0.2))])
        with sim:
            for _ in range(5):
                sim.step_once()
            steps, phase, check = [], [], []
            for _ in range(args.steps):
                timings = sim.step_once(return_profiling=True)
                assert timings is not None
                steps.append(timings["total"])
                phase.append(timings["safety_fields"])
                check.append(timings["collision_check"])
            stopped = len(sim.safety.stopped_agents())
    print(
        f"{WIDTH} x {HEIGHT} map: {len(loaded.lo)} obstacle boxes in {len(loaded.bodies)} bodies, "
        f"loaded in {t_map:.2f} s; with {args.robots} robots spawned: {t_load:.2f} s"
    )
    print(
        f"step (median of {args.steps}): {statistics.median(steps):.2f} ms, of which "
        f"safety_fields {statistics.median(phase):.2f} ms, collision_check "
        f"{statistics.median(check):.2f} ms; {stopped} robots stopped at the end"
    )


if __name__ == "__main__":
    main()
