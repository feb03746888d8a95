"""A trace beside skipped steps: a sparse fleet run untraced, traced, and traced the old way.

The workload: N box robots (default 2,000), each driven by a mission that waits about a
minute of sim time, moves 1 m, and does that six times; timestep 0.1 s. Almost every step is
empty, so the mission driver skips them (``sim.skip_idle_steps``). Three runs of the same
workload: untraced; traced (``sim.start_trace``: frames from a step observer, a skipped span
written as its first and last frame slots); and traced through a POST_STEP handler, as the
viewer branch's writer was hooked in, which makes every step count for ``sim.idle_steps``, so
nothing is skipped and every step writes a frame. Reported per run: steps, steps run and
skipped, wall time, and the trace's frames and size; then whether every frame of the
per-step trace equals the frame of the skipping trace at or before its step (the viewer shows
the same run).

Run:  python benchmarks/trace_skip_bench.py [--n 2000] [--trips 6]
"""

from __future__ import annotations

import argparse
import bisect
import os
import tempfile
import time
from typing import Any

import numpy as np

import fleet_async as fa
from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimulationParams,
)
from fleet_async.core.base.events import SimEvents
from fleet_async.viewer import TraceReader

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def build(n: int) -> tuple[MultiRobotSimulationCore, list[Agent]]:
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, monitor=False, target_rtf=0, timestep=0.1)
    )
    robots = [
        Agent.from_params(
            AgentSpawnParams(
                visual_shape=BOX,
                collision_shape=BOX,
                initial_pose=Pose.from_xyz(i % 50, i // 50 * 2, 0.1),
                controller={"type": "omni", "max_linear_vel": 1.0},
            ),
            sim,
        )
        for i in range(n)
    ]
    return sim, robots


async def shift(sim: MultiRobotSimulationCore, robots: list[Agent], trips: int) -> None:
    async def shuttle(robot: Agent, k: int) -> None:
        for trip in range(trips):
            await sim.sleep(60.0 + k * 0.1)
            x, y, _ = robot.get_pose().position
            await robot.move(Pose.from_xyz(x, y + (1 if trip % 2 == 0 else -1), 0.1))

    async with sim.task_group() as tg:
        for k, robot in enumerate(robots):
            tg.start_soon(shuttle, robot, k % 5)


def one_run(n: int, trips: int, mode: str, path: str | None) -> dict[str, Any]:
    sim, robots = build(n)
    ran, skipped = [0], [0]

    def count_run(step: int) -> None:
        ran[0] += 1

    def count_skipped(count: int, **_: Any) -> None:
        skipped[0] += count

    sim.add_step_observer(count_run)
    sim.events.on(SimEvents.STEPS_SKIPPED, count_skipped)
    if path is not None:
        writer = sim.start_trace(path)
        if mode == "post_step":  # hooked in as the viewer branch's writer was
            observer = writer._after_step  # noqa: SLF001
            sim.remove_step_observer(observer)
            sim.events.on(SimEvents.POST_STEP, lambda step, **_: observer(step))
    t0 = time.perf_counter()
    fa.run(sim, shift, sim, robots, trips)
    wall = time.perf_counter() - t0
    sim.close()  # finishes the trace
    return {"steps": sim.step_count, "run": ran[0], "skipped": skipped[0], "wall_s": wall}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--n", type=int, default=2000, help="robots (default 2000)")
    parser.add_argument("--trips", type=int, default=6, help="moves per robot (default 6)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        paths = {
            "untraced": None,
            "traced": f"{tmp}/new.fatrace",
            "post_step": f"{tmp}/old.fatrace",
        }
        for mode, path in paths.items():
            row = one_run(args.n, args.trips, mode, path)
            line = (
                f"{mode:>10}: {row['steps']} steps, {row['run']} run, {row['skipped']} skipped, "
                f"wall {row['wall_s']:.2f} s"
            )
            if path is not None:
                frames = TraceReader(path).frame_count
                line += f"; {frames} frames, {os.path.getsize(path) / 1e6:.1f} MB"
            print(line)
        new = list(TraceReader(paths["traced"]).frames())
        steps = [f.step for f in new]
        differ = 0
        for frame in TraceReader(paths["post_step"]).frames():
            held = new[bisect.bisect_right(steps, frame.step) - 1]
            same = np.array_equal(held.position, frame.position)
            differ += not (same and np.array_equal(held.yaw, frame.yaw))
        print(f"frames of the per-step trace that differ from the skipping trace's: {differ}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
