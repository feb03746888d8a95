"""The fleet and spawning workloads written once against the reference API's modules.

The same code runs on fleet_async and on pybullet-fleet 0.8.0 (the incumbent): ``--package``
picks which package's ``agent`` / ``core_simulation`` / ``geometry`` / ``sim_object`` / ``types``
modules it imports, the way a user's script ports by renaming its imports. It prints one JSON
object per run. ``fleet_bench.py --incumbent`` and ``spawn_bench.py --incumbent`` run it with the
incumbent's interpreter so both sides are measured in the same run of the benchmark.

Workloads:

- ``fleet N``: N box robots (0.1 m cube, kinematic, omni, 2 m/s, 3 rad/s) on a ceil(sqrt(N))
  grid, 1 m apart at z = 0.1, spawned with ``Agent.from_params`` inside ``sim.batch_spawn()``;
  half of them (fixed seed) get a goal uniform in (-10, g + 10) on x and y; dt 0.1 s, collision
  checks every step (CLOSEST_POINTS, margin 0.02 m); 10 warm-up steps, then 100 timed
  ``step_once()`` calls. The same workload as ``fleet_async.bench``.
- ``spawn N``: a plain loop of ``Agent.from_mesh`` (the benchmark's cube) or ``Agent.from_urdf``
  (a shared model, ``mass=0.0``) with ``sim_core=sim``, as users write it, on a ceil(sqrt(N))
  grid (``--spacing``: 1 m for the cube, 2 m otherwise, so that robots such as husky, 1 m
  long, do not overlap) (``--kind loaded``: each robot
  ``Agent.from_params`` with an omni + patrol controller and a battery, then a tote of the same
  box shape ``SimObject.from_mesh`` and ``robot.attach_object(tote)``: the loop that went
  quadratic), timed up to the end of the first
  ``step_once()`` so that work an implementation defers to the step is counted (``spawn_s``);
  then ``sim.client`` is read, as raw PyBullet calls do, and its time reported apart
  (``bodies_s``; ``*_cpu_s``: the process's CPU time): fleet_async creates the PyBullet
  bodies a kinematic fleet never needed then, pybullet-fleet has nothing left to do.

- ``realistic N``: the realistic fleet in seed-API terms (what both packages have of
  ``fleet-async bench --realistic``): N robots (box, omni, 1.5 m/s) on a grid 4 m apart, each
  with a battery; a third patrol a 1.5 m square (``patrol``, 1 s wait), a third wander
  (``random_walk``, radius 1.5 m, waits 0.5-3 s), a third run an action queue of 20 rounds
  (move 1.5 m, charge 2-10 s, move home, wait 1-5 s: the missions as actions); every other
  robot carries a tote (attached), one in ten has a 1 Hz per-object callback; collision
  checks every step. Spawned one call at a time, timed to the end of the first step
  (``spawn_s``); then 50 warm-up steps and 200 timed ``step_once()`` calls (``step_ms``;
  ``*_cpu_*``: the process's CPU time, steadier than wall time on a shared machine).

Run:  python benchmarks/seed_api_workloads.py --package fleet_async fleet 1000
      /tmp/pbf/bin/python benchmarks/seed_api_workloads.py --package pybullet_fleet spawn 10000
"""

from __future__ import annotations

import argparse
import gc
import importlib
import json
import math
import time
from typing import Any

WARMUP_STEPS = 10
TIMED_STEPS = 100
SEED = 42


def _modules(package: str) -> dict[str, Any]:
    return {
        name: importlib.import_module(f"{package}.{name}")
        for name in ("agent", "core_simulation", "geometry", "sim_object", "types")
    }


def _sim(m: dict[str, Any], kernels: str | None = None) -> Any:
    extra = {} if kernels is None else {"kernels": kernels}  # fleet_async's own setting
    params = m["core_simulation"].SimulationParams(
        gui=False,
        monitor=False,
        target_rtf=0.0,
        timestep=0.1,
        collision_detection_method=m["types"].CollisionDetectionMethod.CLOSEST_POINTS,
        collision_margin=0.02,
        collision_check_frequency=None,
        enable_floor=False,
        **extra,
    )
    return m["core_simulation"].MultiRobotSimulationCore(params)


def _timed_steps(sim: Any, warmup: int, steps: int) -> tuple[float, float]:
    """Collect garbage, run ``warmup`` steps, then time ``steps``: (wall ms, CPU ms) per step.

    The collection comes before the warm-up, not after: a collection walks the whole heap, and
    the step right after it runs on cold caches (at 100 robots 4-6x slower than the next).
    """
    gc.collect()
    for _ in range(warmup):
        sim.step_once()
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        sim.step_once()
    return (
        (time.perf_counter() - t0) * 1000.0 / steps,
        (time.process_time() - c0) * 1000.0 / steps,
    )


def _close(sim: Any) -> None:
    import pybullet as p

    p.disconnect(physicsClientId=sim.client)


def fleet(m: dict[str, Any], n: int) -> dict[str, Any]:
    """Step time of the fleet workload (see the module docstring)."""
    import numpy as np

    agent_mod, pose_cls = m["agent"], m["geometry"].Pose
    sim = _sim(m)
    side = math.ceil(math.sqrt(n))
    cube = m["sim_object"].ShapeParams(shape_type="box", half_extents=[0.05, 0.05, 0.05])
    controller = {"type": "omni", "max_linear_vel": 2.0, "max_angular_vel": 3.0}
    t0 = time.perf_counter()
    with sim.batch_spawn():
        agents = [
            agent_mod.Agent.from_params(
                agent_mod.AgentSpawnParams(
                    visual_shape=cube,
                    collision_shape=cube,
                    initial_pose=pose_cls.from_xyz(float(i % side), float(i // side), 0.1),
                    mass=0.0,
                    controller=controller,
                ),
                sim_core=sim,
            )
            for i in range(n)
        ]
    spawn_s = time.perf_counter() - t0
    rng = np.random.default_rng(SEED)
    movers = rng.choice(n, size=n // 2, replace=False)
    goals = rng.uniform(-10.0, side + 10.0, size=(len(movers), 2))
    for idx, (gx, gy) in zip(movers.tolist(), goals.tolist(), strict=True):
        agents[idx].set_goal_pose(pose_cls.from_xyz(gx, gy, 0.1))
    step_ms, step_cpu_ms = _timed_steps(sim, WARMUP_STEPS, TIMED_STEPS)
    _close(sim)
    return {
        "workload": "fleet",
        "n": n,
        "step_ms": step_ms,
        "step_cpu_ms": step_cpu_ms,
        "spawn_s": spawn_s,
    }


def spawn(
    m: dict[str, Any], n: int, kind: str, model: str, spacing: float | None = None
) -> dict[str, Any]:
    """Wall and CPU time of a per-agent spawning loop, up to the end of the first step."""
    agent_cls, pose_cls = m["agent"].Agent, m["geometry"].Pose
    sim = _sim(m)
    side = math.ceil(math.sqrt(n))
    gap = spacing if spacing is not None else (1.0 if kind == "mesh" else 2.0)
    cube = m["sim_object"].ShapeParams(shape_type="box", half_extents=[0.05, 0.05, 0.05])
    controller = {"type": "omni", "max_linear_vel": 2.0, "max_angular_vel": 3.0}
    gc.collect()
    t0, c0 = time.perf_counter(), time.process_time()
    if kind == "loaded":  # issue 28's loop: controllers, a battery, a tote attached
        body = m["sim_object"].ShapeParams(shape_type="box", half_extents=[0.3, 0.2, 0.1])
        tote = m["sim_object"].ShapeParams(shape_type="box", half_extents=[0.3, 0.2, 0.1])
        for i in range(n):
            x, y = gap * (i % side), gap * (i // side)
            robot = m["agent"].Agent.from_params(
                m["agent"].AgentSpawnParams(
                    visual_shape=body,
                    collision_shape=body,
                    initial_pose=pose_cls.from_xyz(x, y, 0.1),
                    mass=0.0,
                    controller=[
                        controller,
                        {"type": "patrol", "waypoints": [[x, y, 0.1], [x + 1.0, y, 0.1]]},
                    ],
                    plugins=[{"type": "battery"}],
                ),
                sim_core=sim,
            )
            box = m["sim_object"].SimObject.from_mesh(
                visual_shape=tote,
                collision_shape=tote,
                pose=pose_cls.from_xyz(x, y, 0.3),
                mass=0.0,
                sim_core=sim,
            )
            robot.attach_object(box, relative_pose=pose_cls.from_xyz(0.0, 0.0, 0.2))
    elif kind == "mesh":
        for i in range(n):
            agent_cls.from_mesh(
                visual_shape=cube,
                collision_shape=cube,
                pose=pose_cls.from_xyz(gap * (i % side), gap * (i // side), 0.1),
                mass=0.0,
                sim_core=sim,
                controller=controller,
            )
    else:
        for i in range(n):
            agent_cls.from_urdf(
                urdf_path=model,
                pose=pose_cls.from_xyz(gap * (i % side), gap * (i // side), 0.1),
                mass=0.0,
                sim_core=sim,
                controller=controller,
            )
    loop_s = time.perf_counter() - t0
    sim.step_once()
    total_s, total_cpu_s = time.perf_counter() - t0, time.process_time() - c0
    # Raw PyBullet access: fleet_async creates the bodies it had no need for until now.
    t1, c1 = time.perf_counter(), time.process_time()
    p_client = sim.client
    bodies_s, bodies_cpu_s = time.perf_counter() - t1, time.process_time() - c1
    del p_client
    _close(sim)
    return {
        "workload": f"spawn_{kind}",
        "n": n,
        "loop_s": loop_s,
        "spacing_m": gap,
        "spawn_s": total_s,
        "spawn_cpu_s": total_cpu_s,
        "bodies_s": bodies_s,
        "bodies_cpu_s": bodies_cpu_s,
    }


def _realistic_robot(m: dict[str, Any], sim: Any, i: int, side: int, rng: Any) -> None:
    """One robot of the realistic workload (see the module docstring)."""
    pose_cls, shape = m["geometry"].Pose, m["sim_object"].ShapeParams
    body = shape(shape_type="box", half_extents=[0.3, 0.2, 0.1])
    tote = shape(shape_type="box", half_extents=[0.15, 0.15, 0.1])
    x, y = 4.0 * (i % side), 4.0 * (i // side)
    controller: list[dict[str, Any]] = [
        {"type": "omni", "max_linear_vel": 1.5, "max_angular_vel": 2.0}
    ]
    role = i % 3
    if role == 0:
        square = [[x + 1.5, y, 0.1], [x + 1.5, y + 1.5, 0.1], [x, y + 1.5, 0.1], [x, y, 0.1]]
        controller.append({"type": "patrol", "waypoints": square, "wait_time": 1.0})
    elif role == 1:
        controller.append({"type": "random_walk", "radius": 1.5, "wait_range": [0.5, 3.0]})
    battery = {"initial_soc": 0.5 + 0.5 * rng.random(), "charge_rate": 0.01}
    robot = m["agent"].Agent.from_params(
        m["agent"].AgentSpawnParams(
            visual_shape=body,
            collision_shape=body,
            initial_pose=pose_cls.from_xyz(x, y, 0.1),
            mass=0.0,
            controller=controller,
            plugins=[{"type": "battery", "config": battery}],
        ),
        sim_core=sim,
    )
    if i % 2 == 0:
        box = m["sim_object"].SimObject.from_mesh(
            visual_shape=tote,
            collision_shape=tote,
            pose=pose_cls.from_xyz(x, y, 0.3),
            mass=0.0,
            sim_core=sim,
        )
        robot.attach_object(box, relative_pose=pose_cls.from_xyz(0.0, 0.0, 0.2))
    if i % 10 == 0:
        robot.register_callback(lambda *_: None, 1.0)  # 1 Hz here, a 1 s period there
    if role == 2:
        action, path = m["action"], m["geometry"].Path
        here, there = pose_cls.from_xyz(x, y, 0.1), pose_cls.from_xyz(x + 1.5, y, 0.1)
        queue = []
        for _ in range(20):
            queue += [
                action.MoveAction(path=path([there])),
                action.WaitAction(duration=float(rng.uniform(2.0, 10.0)), action_type="charge"),
                action.MoveAction(path=path([here])),
                action.WaitAction(duration=float(rng.uniform(1.0, 5.0))),
            ]
        robot.add_action_sequence(queue)


def realistic(
    m: dict[str, Any], n: int, steps: int = 200, kernels: str | None = None
) -> dict[str, Any]:
    """Spawn and step time of the realistic workload (see the module docstring)."""
    import numpy as np

    m["action"] = importlib.import_module(f"{m['agent'].__name__.rsplit('.', 1)[0]}.action")
    sim = _sim(m, kernels)
    side = math.ceil(math.sqrt(n))
    rng = np.random.default_rng(SEED)
    gc.collect()
    t0, c0 = time.perf_counter(), time.process_time()
    for i in range(n):
        _realistic_robot(m, sim, i, side, rng)
    sim.step_once()
    spawn_s, spawn_cpu_s = time.perf_counter() - t0, time.process_time() - c0
    step_ms, step_cpu_ms = _timed_steps(sim, 50, steps)
    fleet = getattr(sim, "fleet", None)
    _close(sim)
    return {
        "workload": "realistic",
        "n": n,
        "step_ms": step_ms,
        "step_cpu_ms": step_cpu_ms,
        "spawn_s": spawn_s,
        "spawn_cpu_s": spawn_cpu_s,
        **({} if kernels is None else {"kernels": "numba" if fleet.compiled else "numpy"}),
    }


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: run one workload and print its JSON result."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--package", default="fleet_async", help="fleet_async or pybullet_fleet")
    sub = parser.add_subparsers(dest="workload", required=True)
    fleet_p = sub.add_parser("fleet", help="step time of the fleet workload")
    fleet_p.add_argument("n", type=int)
    spawn_p = sub.add_parser("spawn", help="per-agent spawning loop + first step")
    spawn_p.add_argument("n", type=int)
    spawn_p.add_argument("--kind", choices=("mesh", "urdf", "loaded"), default="mesh")
    spawn_p.add_argument("--model", default="mobile_robot", help="URDF model for --kind urdf")
    spawn_p.add_argument(
        "--spacing", type=float, default=None, help="grid spacing, m (default 1 mesh, 2 others)"
    )
    real_p = sub.add_parser("realistic", help="the realistic fleet in seed-API terms")
    real_p.add_argument("n", type=int)
    real_p.add_argument("--steps", type=int, default=200, help="timed steps (default 200)")
    real_p.add_argument(
        "--kernels", default=None, help="fleet_async's SimulationParams.kernels (default: its own)"
    )
    args = parser.parse_args(argv)
    m = _modules(args.package)
    if args.workload == "fleet":
        result = fleet(m, args.n)
    elif args.workload == "realistic":
        result = realistic(m, args.n, args.steps, args.kernels)
    else:
        result = spawn(m, args.n, args.kind, args.model, args.spacing)
    result["package"] = args.package
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
