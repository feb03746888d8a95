"""Mission overhead at fleet scale: N robots each under its own mission, against action queues.

Workload (issue 28, item 6): N box robots (0.1 m cube, omni, 2 m/s) in a row 3 m apart, each
0.5 m behind its home spot, with a tote (a pickable 0.1 m cube) 2 m in front of that spot.
Every robot loops

    move to its home spot -> wait 0.5 s -> pick its tote -> drop it on the other side (2 m
    behind the home spot, then 2 m in front, and so on)

(the pick and the drop drive their approach, act and retreat stages: each loop is about 80
steps of 0.1 s). Run once with every robot under its own mission (``fleet_async.run``, on
asyncio and on trio: ``await robot.move(...)``, ``await robot.wait(0.5)``, ``await
robot.pick(tote)``, ``await robot.drop(...)``), and once as the seed API does it: each robot's
action queue holds the same MoveAction / WaitAction / PickAction / DropAction sequence, and the
next loop's four are queued when the last one completes (an ``action_completed`` handler, as a
careful synchronous user writes it; ``--prequeued`` queues every loop of the run up front
instead, which costs no handler at all). No collision checks: the figure is the mission
layer's cost over the queues', and the rest of the step is the same in both.

``--workload waits`` is the worst case for missions: no totes, and every robot loops a
WaitAction of one step (``await robot.wait(0.1)``), an action that costs the queue almost
nothing, so what is left is the mission layer's own cost per action.

Each run is a fresh process (the bodies are made before it is timed). Both runs cover the
same sim time, ``--warmup`` untimed steps then ``--steps`` timed ones, and must end in the
same state: every robot's and tote's pose, what each robot carries, and how
many actions each robot completed (checked after every run; ``tests/tasks/test_fleet_bench.py``
checks it at small N). Times are CPU seconds of this process (``time.process_time``); each
mode runs ``--repeat`` times, interleaved (the order rotates each round), and the medians
and the median of the per-round ratios are reported, with the load average before and after
(``--parallel``: each round's modes run at the same time, in their own processes).

Run:  python benchmarks/mission_fleet_bench.py [--agents 10000] [--steps 300] [--warmup 10]
          [--repeat 5] [--prequeued] [--workload loop|waits] [--modes queues asyncio trio]
          [--profile MODE] [--json]
"""

from __future__ import annotations

import argparse
import cProfile
import gc
import json
import os
import pstats
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

import fleet_async as fa
from fleet_async import (
    Action,
    Agent,
    AgentSpawnParams,
    DropAction,
    MoveAction,
    MultiRobotSimulationCore,
    PickAction,
    Pose,
    ShapeParams,
    SimObject,
    SimulationParams,
    WaitAction,
)

MODES = ("queues", "asyncio", "trio")
SPACING = 3.0
"""m between neighbouring robots (their totes never come near another robot)."""
REACH = 2.0
"""m from the home spot to where a tote lies, in front (+y) or behind (-y)."""
START = -0.5
"""m: robots start this far from their home spot (y = 0), so that no action of the run ends
in the step it starts: a queue starts the next action in that same step, a mission only once
it resumed (at the step's end), and the two runs would drift apart by a step."""
Z = 0.1
TICK = 0.1
"""s: the wait of the ``waits`` workload (one step)."""
_clock = time.process_time


class GcTally:
    """Collections by generation and their CPU time, while on (the timed steps)."""

    def __init__(self) -> None:
        self.on = False
        self.count = [0, 0, 0]
        self.seconds = 0.0
        self._t0 = 0.0
        self.last: dict[str, Any] = {}
        gc.callbacks.append(self._callback)

    def _callback(self, phase: str, info: dict[str, int]) -> None:
        if not self.on:
            return
        if phase == "start":
            self._t0 = _clock()
        else:
            self.count[info["generation"]] += 1
            self.seconds += _clock() - self._t0

    def start(self) -> None:
        self.on, self.count, self.seconds = True, [0, 0, 0], 0.0

    def stop(self) -> None:
        self.on = False
        self.last = {"collections": list(self.count), "seconds": self.seconds}


GC = GcTally()


def params() -> SimulationParams:
    """Headless, unpaced, dt 0.1 s, no collision checks."""
    return SimulationParams(
        gui=False,
        monitor=False,
        target_rtf=0.0,
        timestep=0.1,
        enable_floor=False,
        collision_check_frequency=0,
    )


@dataclass
class Fleet:
    """The robots and their totes, and how many actions each robot completed."""

    sim: MultiRobotSimulationCore
    robots: list[Agent]
    totes: list[SimObject]
    completed: dict[int, int]


def build(n: int, totes: bool = True) -> Fleet:
    """A fresh simulation with ``n`` robots and (unless ``totes`` is False) their totes (see
    the module doc)."""
    sim = MultiRobotSimulationCore(params())
    cube = ShapeParams("box", half_extents=[0.05, 0.05, 0.05])
    robots = Agent.spawn_batch(
        [
            AgentSpawnParams(
                visual_shape=cube,
                collision_shape=cube,
                initial_pose=Pose.from_xyz(SPACING * i, START, Z),
                controller={"type": "omni", "max_linear_vel": 2.0},
            )
            for i in range(n)
        ],
        sim,
    )
    boxes = [
        SimObject.from_mesh(cube, cube, Pose.from_xyz(SPACING * i, REACH, Z), sim_core=sim)
        for i in range(n if totes else 0)
    ]
    for tote in boxes:
        tote.pickable = True
    (boxes or robots)[0].body_id  # noqa: B018  # bodies are made now, not in the timed steps
    completed = {robot.object_id: 0 for robot in robots}

    def count(agent: Agent, **_: Any) -> None:
        completed[agent.object_id] += 1

    sim.events.on("action_completed", count)
    return Fleet(sim, robots, boxes, completed)


def loop_actions(column: float, tote: SimObject, lap: int) -> list[Action]:
    """The four actions of loop ``lap`` (0, 1, ...) of the robot in ``column`` (its x, m):
    the tote lies in front at lap 0 and goes behind, then in front again, and so on."""
    side = -REACH if lap % 2 == 0 else REACH
    return [
        MoveAction(path=Pose.from_xyz(column, 0.0, Z)),
        WaitAction(duration=0.5),
        PickAction(target_object_id=tote),
        DropAction(drop_pose=Pose.from_xyz(column, side, Z)),
    ]


def run_queues(
    fleet: Fleet, steps: int, warmup: int, prequeued: bool = False, workload: str = "loop"
) -> float:
    """ms per step (CPU) of the timed steps with the work queued as actions."""
    sim = fleet.sim
    laps = {robot.object_id: 0 for robot in fleet.robots}
    last: dict[int, Action] = {}
    totes: list[Any] = list(fleet.totes) or [None] * len(fleet.robots)
    pairs = enumerate(zip(fleet.robots, totes, strict=True))
    work = {robot.object_id: (SPACING * i, tote) for i, (robot, tote) in pairs}

    def queue(robot: Agent) -> None:
        key = robot.object_id
        column, tote = work[key]
        if workload == "waits":
            seq: list[Action] = [WaitAction(duration=TICK)]
        else:
            seq = loop_actions(column, tote, laps[key])
        laps[key] += 1
        last[key] = seq[-1]
        robot.add_action_sequence(seq)

    if prequeued:
        per_lap = 1 if workload == "waits" else 70  # steps a lap takes at least
        for robot in fleet.robots:
            for _ in range((warmup + steps) // per_lap + 2):
                queue(robot)
    else:

        def on_done(agent: Agent, action: Any, **_: Any) -> None:
            if last.get(agent.object_id) is action:
                queue(agent)

        sim.events.on("action_completed", on_done)
        for robot in fleet.robots:
            queue(robot)
    for _ in range(warmup):
        sim.step_once()
    GC.start()
    t0 = _clock()
    for _ in range(steps):
        sim.step_once()
    elapsed = _clock() - t0
    GC.stop()
    return elapsed * 1e3 / steps


def run_missions(
    fleet: Fleet, steps: int, warmup: int, backend: str, workload: str = "loop"
) -> float:
    """ms per step (CPU) of the timed steps with every robot under its own mission."""
    sim = fleet.sim

    async def waiter(robot: Agent) -> None:
        while True:
            await robot.wait(TICK)

    async def worker(robot: Agent, column: float, tote: SimObject) -> None:
        lap = 0
        while True:
            await robot.move(Pose.from_xyz(column, 0.0, Z))
            await robot.wait(0.5)
            await robot.pick(tote)
            side = -REACH if lap % 2 == 0 else REACH
            await robot.drop(Pose.from_xyz(column, side, Z))
            lap += 1

    async def main() -> None:
        async with sim.task_group() as tg:
            if workload == "waits":
                for robot in fleet.robots:
                    tg.start_soon(waiter, robot)
                return
            for i, (robot, tote) in enumerate(zip(fleet.robots, fleet.totes, strict=True)):
                tg.start_soon(worker, robot, SPACING * i, tote)

    started: list[float] = []

    def clock(step: int, **_: Any) -> None:
        if step == warmup:
            GC.start()
            started.append(_clock())

    sim.events.on("post_step", clock)
    fa.run(sim, main, backend=backend, until=(warmup + steps) * sim.params.timestep)
    elapsed = _clock() - started[0]
    GC.stop()
    sim.events.off("post_step", clock)
    return elapsed * 1e3 / steps


def state(fleet: Fleet) -> dict[str, Any]:
    """What both runs must agree on: poses, who carries what, actions completed."""
    sim = fleet.sim
    return {
        "step": sim.step_count,
        "robots": np.array([r.get_pose().position for r in fleet.robots]),
        "totes": np.array([t.get_pose().position for t in fleet.totes]).reshape(-1, 3),
        "carried": [t.is_attached() for t in fleet.totes],
        "completed": [fleet.completed[r.object_id] for r in fleet.robots],
    }


def same_state(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Whether two :func:`state` results are identical (poses to the bit)."""
    return (
        a["step"] == b["step"]
        and np.array_equal(a["robots"], b["robots"])
        and np.array_equal(a["totes"], b["totes"])
        and a["carried"] == b["carried"]
        and a["completed"] == b["completed"]
    )


def run_mode(
    mode: str, n: int, steps: int, warmup: int, prequeued: bool = False, workload: str = "loop"
) -> tuple[float, dict[str, Any]]:
    """One run of ``mode`` (``queues``, ``asyncio`` or ``trio``) in a fresh simulation:
    (ms per step, end state)."""
    fleet = build(n, totes=workload != "waits")
    try:
        gc.collect()
        if mode == "queues":
            ms = run_queues(fleet, steps, warmup, prequeued, workload)
        else:
            ms = run_missions(fleet, steps, warmup, mode, workload)
        return ms, {**state(fleet), "gc": GC.last}
    finally:
        fleet.sim.close()


def start_child(
    mode: str, n: int, steps: int, warmup: int, prequeued: bool, workload: str
) -> subprocess.Popen[str]:
    """Start :func:`run_mode` in a fresh process (each run starts from the same heap, and the
    child exits without the minutes a 20,000-body PyBullet disconnect takes)."""
    args = [sys.executable, __file__, "--child", mode, "--agents", str(n), "--steps", str(steps)]
    args += ["--warmup", str(warmup), "--workload", workload]
    args += ["--prequeued"] if prequeued else []
    return subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finish_child(mode: str, child: subprocess.Popen[str]) -> tuple[float, dict[str, Any]]:
    """Wait for a child of :func:`start_child`: (ms per step, end state)."""
    out, err = child.communicate()
    lines = [line for line in out.splitlines() if line.startswith("{")]
    if child.returncode != 0 or not lines:
        raise RuntimeError(f"{mode} run failed:\n{out}\n{err}")
    result = json.loads(lines[-1])
    end = result["state"]
    for key in ("robots", "totes"):
        end[key] = np.array(end[key], dtype=float).reshape(-1, 3)
    return result["ms"], end


def _child(mode: str, n: int, steps: int, warmup: int, prequeued: bool, workload: str) -> None:
    fleet = build(n, totes=workload != "waits")
    gc.collect()
    if mode == "queues":
        ms = run_queues(fleet, steps, warmup, prequeued, workload)
    else:
        ms = run_missions(fleet, steps, warmup, mode, workload)
    end = {**state(fleet), "gc": GC.last}
    for key in ("robots", "totes"):
        end[key] = end[key].tolist()  # floats survive JSON exactly (repr round-trips)
    print(json.dumps({"ms": ms, "state": end}), flush=True)
    os._exit(0)  # skip closing PyBullet: the parent has what it needs


def _load() -> str:
    return "/".join(f"{x:.2f}" for x in os.getloadavg())


def measure(
    n: int,
    steps: int,
    warmup: int,
    repeat: int,
    modes: tuple[str, ...] = MODES,
    prequeued: bool = False,
    workload: str = "loop",
    parallel: bool = False,
    report: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Interleaved runs of every mode; raises AssertionError if two runs end differently."""
    times: dict[str, list[float]] = {mode: [] for mode in modes}
    gcs: dict[str, list[dict[str, Any]]] = {mode: [] for mode in modes}
    reference: dict[str, Any] | None = None
    load_before = _load()
    for round_ in range(repeat):
        order = modes[round_ % len(modes) :] + modes[: round_ % len(modes)]
        children = {}
        for mode in order:  # one after the other, or all at once with ``parallel``
            children[mode] = start_child(mode, n, steps, warmup, prequeued, workload)
            if not parallel:
                children[mode] = finish_child(mode, children[mode])
        for mode in modes:
            ms, end = children[mode] if not parallel else finish_child(mode, children[mode])
            if reference is None:
                reference = end
            elif not same_state(reference, end):
                raise AssertionError(f"{mode} run {round_} ended in another state")
            times[mode].append(ms)
            gcs[mode].append(end["gc"])
            report(
                f"  round {round_} {mode:<8} {ms:8.3f} ms/step (load {_load()}; GC "
                f"{end['gc']['collections']} collections, {end['gc']['seconds']:.2f} s)"
            )
    result: dict[str, Any] = {
        "agents": n,
        "steps": steps,
        "warmup": warmup,
        "repeat": repeat,
        "prequeued": prequeued,
        "workload": workload,
        "parallel": parallel,
        "load_before": load_before,
        "load_after": _load(),
        "ms_per_step": times,
        "gc": gcs,
        "median_ms": {mode: statistics.median(v) for mode, v in times.items()},
        "completed_actions": sum(reference["completed"]) if reference else 0,
    }
    if "queues" in times:
        base = times["queues"]
        result["ratio_of_medians"] = {
            mode: statistics.median(v) / statistics.median(base)
            for mode, v in times.items()
            if mode != "queues"
        }
        result["median_ratio"] = {
            mode: statistics.median(a / b for a, b in zip(v, base, strict=True))
            for mode, v in times.items()
            if mode != "queues"
        }
    return result


def profile(
    mode: str, n: int, steps: int, warmup: int, prequeued: bool, workload: str, top: int
) -> None:
    """cProfile one run of ``mode``; print the top functions by internal time."""
    profiler = cProfile.Profile()
    profiler.enable()
    run_mode(mode, n, steps, warmup, prequeued, workload)
    profiler.disable()
    pstats.Stats(profiler).sort_stats("tottime").print_stats(top)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agents", type=int, default=10_000)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--warmup", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--modes", nargs="+", choices=MODES, default=list(MODES))
    parser.add_argument("--prequeued", action="store_true")
    parser.add_argument("--workload", choices=("loop", "waits"), default="loop")
    parser.add_argument("--profile", choices=MODES, default=None)
    parser.add_argument("--top", type=int, default=40)
    parser.add_argument("--json", action="store_true")
    parser.add_argument(
        "--parallel",
        action="store_true",
        help="run each round's modes at the same time, one process each (CPU times, paired "
        "under the same load; for a machine too busy to run them one after the other)",
    )
    parser.add_argument("--child", choices=MODES, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        _child(args.child, args.agents, args.steps, args.warmup, args.prequeued, args.workload)
    if args.profile:
        profile(
            args.profile,
            args.agents,
            args.steps,
            args.warmup,
            args.prequeued,
            args.workload,
            args.top,
        )
        return 0
    result = measure(
        args.agents,
        args.steps,
        args.warmup,
        args.repeat,
        tuple(args.modes),
        args.prequeued,
        args.workload,
        args.parallel,
    )
    if args.json:
        print(json.dumps(result))
        return 0
    print(
        f"{args.agents} robots, {args.steps} timed steps after {args.warmup}, "
        f"{args.repeat} interleaved rounds, load {result['load_before']} -> "
        f"{result['load_after']}, {result['completed_actions']} actions completed; "
        "every run ended in the same state"
    )
    for mode, ms in result["median_ms"].items():
        line = f"  {mode:<8} median {ms:8.3f} ms/step"
        if mode != "queues" and "median_ratio" in result:
            line += (
                f"  {result['ratio_of_medians'][mode]:.3f}x queues "
                f"(median of round ratios {result['median_ratio'][mode]:.3f}x)"
            )
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
