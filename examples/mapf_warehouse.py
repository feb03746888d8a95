"""A MAPF benchmark map with a thousand robots: safety fields on, each robot driving to its goal.

Run:  python examples/mapf_warehouse.py [--map FILE.map] [--scen FILE.scen] [--robots 1000]
                                        [--duration 60] [--max-steps N]

The map is a MovingAI ``.map`` file (the maps of the MAPF benchmarks and the League of Robot
Runners), loaded as static obstacles with ``sim.load_map`` (cells of ``--cell`` metres). Without
``--map`` it is the benchmark set's own warehouse-10-20-10-2-1 (161 x 63 cells), shipped beside
this script in ``maps/`` (source and licence in ``maps/README.md``). Start and goal cells come
from a ``.scen`` file in its order (``--scen``), or are drawn from the simulation's random
generator on free cells.

Robots drive, they do not plan: each takes the shortest route of at most three straight legs
(along its row, a column, the goal's row; or the other way round) that stays on free cells, and
a task without one is left out. What makes the run interesting is that the routes ignore each
other: every robot has safety fields, so robots stop for each other where their routes meet,
queue, and block each other head-on. The summary counts the robots that arrived, the stops,
the time stopped and the deadlocks suspected (the blocked sets a MAPF planner or a traffic
controller would have avoided), and the collisions, which the fields prevent.
"""

from __future__ import annotations

import argparse
import math
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
from fleet_async.core.maps.readers import read_movingai_scen

BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.2])  # 0.6 x 0.4 m robots on 1 m cells, 1 m/s
WAREHOUSE = Path(__file__).resolve().parent / "maps" / "warehouse-10-20-10-2-1.map"
FIELDS = {"deceleration": 1.0, "protective_margin": 0.1, "warning_margin": 0.3}


def routes(free: np.ndarray, tasks: np.ndarray) -> list[list[tuple[int, int]] | None]:
    """For each task ``(sx, sy, gx, gy)`` (cells: x column, y row) the corners of its shortest
    route of at most three straight legs on free cells, or None (vectorized over tasks)."""
    blocked = (~free).astype(np.int32)
    h, w = free.shape
    in_row = np.zeros((h, w + 1), dtype=np.int32)  # blocked cells of row y before column x
    in_row[:, 1:] = np.cumsum(blocked, axis=1)
    in_col = np.zeros((w, h + 1), dtype=np.int32)  # blocked cells of column x before row y
    in_col[:, 1:] = np.cumsum(blocked.T, axis=1)

    def clear(cum: np.ndarray, line: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        return cum[line, hi + 1] - cum[line, lo] == 0

    sx, sy, gx, gy = (tasks[:, k : k + 1] for k in range(4))
    cols, rows = np.arange(w)[None, :], np.arange(h)[None, :]
    # Row, column c, row: (sx, sy) -> (c, sy) -> (c, gy) -> (gx, gy).
    ok_c = clear(in_row, sy, sx, cols) & clear(in_col, cols, sy, gy) & clear(in_row, gy, cols, gx)
    cost_c = np.where(ok_c, np.abs(sx - cols) + np.abs(sy - gy) + np.abs(cols - gx), 1 << 30)
    # Column, row r, column: (sx, sy) -> (sx, r) -> (gx, r) -> (gx, gy).
    ok_r = clear(in_col, sx, sy, rows) & clear(in_row, rows, sx, gx) & clear(in_col, gx, rows, gy)
    cost_r = np.where(ok_r, np.abs(sy - rows) + np.abs(sx - gx) + np.abs(rows - gy), 1 << 30)
    best_c, best_r = cost_c.argmin(axis=1), cost_r.argmin(axis=1)
    out: list[list[tuple[int, int]] | None] = []
    for i, (x0, y0, x1, y1) in enumerate(tasks.tolist()):
        c, r = int(best_c[i]), int(best_r[i])
        if min(cost_c[i, c], cost_r[i, r]) >= 1 << 30:
            out.append(None)
            continue
        if cost_c[i, c] <= cost_r[i, r]:
            corners = [(x0, y0), (c, y0), (c, y1), (x1, y1)]
        else:
            corners = [(x0, y0), (x0, r), (x1, r), (x1, y1)]
        route = [corners[0]]
        for p in corners[1:]:
            if p != route[-1]:
                route.append(p)
        out.append(route)
    return out


def pick_tasks(
    free: np.ndarray, robots: int, rng: np.random.Generator, scen: Path | None
) -> tuple[np.ndarray, list[list[tuple[int, int]]], int]:
    """``robots`` tasks with distinct starts and goals and a route each: from ``scen`` in its
    order, or drawn on free cells. Returns (tasks, routes, tasks left out for lack of a route)."""
    if scen is not None:
        candidates = np.array([[*t.start, *t.goal] for t in read_movingai_scen(scen)], dtype=int)
    else:
        cells = np.argwhere(free)[:, ::-1]  # (x, y) of every free cell
        picks = rng.permutation(len(cells))[: 2 * robots]
        half = len(picks) // 2
        candidates = np.column_stack((cells[picks[:half]], cells[picks[half : 2 * half]]))
    found = routes(free, candidates) if len(candidates) else []
    tasks, chosen, skipped = [], [], 0
    starts: set[tuple[int, int]] = set()
    goals: set[tuple[int, int]] = set()
    for task, route in zip(candidates.tolist(), found, strict=True):
        if len(tasks) == robots:
            break
        start, goal = (task[0], task[1]), (task[2], task[3])
        if start in starts or goal in goals:
            continue
        if route is None:
            skipped += 1
            continue
        starts.add(start)
        goals.add(goal)
        tasks.append(task)
        chosen.append(route)
    return np.array(tasks, dtype=int).reshape(-1, 4), chosen, skipped


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--map",
        type=Path,
        default=WAREHOUSE,
        help=f"a MovingAI .map file (default: {WAREHOUSE.name})",
    )
    parser.add_argument("--scen", type=Path, help="a MovingAI .scen file of start / goal cells")
    parser.add_argument("--robots", type=int, default=1000)
    parser.add_argument("--cell", type=float, default=1.0, help="cell edge (m)")
    parser.add_argument("--duration", type=float, default=60.0, help="sim seconds to run")
    parser.add_argument("--max-steps", type=int, default=None, help="stop after this many steps")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if args.robots < 1:
        parser.error(f"--robots: expected a number >= 1, got {args.robots}")

    map_path = args.map
    params = SimulationParams(
        gui=False, monitor=False, target_rtf=0.0, timestep=0.1, seed=args.seed
    )
    with MultiRobotSimulationCore(params) as sim:
        t0 = time.perf_counter()
        grid = sim.load_map(map_path, resolution=args.cell)
        free = ~grid.grid.occupied
        tasks, chosen, skipped = pick_tasks(free, args.robots, sim.rng, args.scen)
        r = args.cell

        def at(x: int, y: int) -> Pose:  # MovingAI cell (x, y) -> its centre (m)
            return Pose.from_xyz((x + 0.5) * r, (y + 0.5) * r, 0.2)

        spawn = [
            AgentSpawnParams(
                visual_shape=BOX,
                collision_shape=BOX,
                initial_pose=at(x, y),
                controller={"type": "omni", "max_linear_vel": 1.0, "max_linear_accel": 1.0},
                safety_field=FIELDS,
                name=f"robot_{k}",
            )
            for k, (x, y, _, _) in enumerate(tasks.tolist())
        ]
        fleet = Agent.spawn_batch(spawn, sim)
        for robot, route in zip(fleet, chosen, strict=True):
            robot.set_path([at(x, y) for x, y in route[1:]] or [at(*route[0])])
        loaded = time.perf_counter() - t0
        steps = math.ceil(args.duration / params.timestep - 1e-9)
        if args.max_steps is not None:
            steps = min(steps, args.max_steps)
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.step_once()
        ran = time.perf_counter() - t0
        report(sim, fleet, tasks, grid.lo, skipped, map_path, loaded, ran, steps)
    return 0


def report(sim, fleet, tasks, boxes, skipped, map_path, loaded, ran, steps) -> None:
    """Print what the fleet did."""
    arrived = sum(1 for robot in fleet if not robot.is_moving)
    stats = sim.safety.stats()
    stops = sum(s for s, _ in stats.values())
    stood = math.fsum(t for _, t in stats.values())
    h, w = sim.maps[0].grid.occupied.shape
    print(f"map: {map_path.name}, {w} x {h} cells, {len(boxes)} obstacle boxes")
    print(
        f"robots: {len(fleet)} ({skipped} tasks left out: no route of three legs), "
        f"loaded and spawned in {loaded:.2f} s"
    )
    per_step = 1000 * ran / max(steps, 1)
    print(f"sim time: {sim.sim_time:.1f} s in {steps} steps ({per_step:.1f} ms a step)")
    print(f"arrived: {arrived} of {len(fleet)} robots at their goals")
    print(
        f"waiting: {stops} safety stops, {stood:.1f} s stopped in all, "
        f"{len(sim.safety.stopped_agents())} robots stopped now, "
        f"{sim.safety.deadlocks_suspected} deadlocks suspected"
    )
    print(f"collisions: {sim.collision_count} (contacts that began)")


if __name__ == "__main__":
    raise SystemExit(main())
