"""A fleet serving random transport orders: how does throughput grow with the fleet size?

Run one shift:   python examples/sweep_fleet.py [--robots 4] [--seed 0] [--max-steps N]
Sweep it:        fleet-async sweep examples/sweep_fleet.py:scenario --seeds 0:20 \\
                     --set robots=1,2,4,6,8 --out fleet.csv --plot fleet.png --x robots

Orders arrive at random (exponential gaps, ``arrival_s`` seconds on average) on a 20 m x 20 m
floor; each asks for a load to be carried from a random pickup point to a random drop point.
Every robot runs a mission: take the next order from the shared queue, drive to the pickup,
load for ``dwell_s``, drive to the drop point, unload, report the task done (a TASK_COMPLETED
event, which ``sim.kpis()`` counts), and take the next. With few robots the fleet is the
bottleneck; with many, the orders are. All randomness comes from the seed, so each (robots,
seed) pair is one reproducible run.
"""

from __future__ import annotations

import argparse

from fleet_async import (
    ActionFailedError,
    Agent,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimulationParams,
    Store,
)

FLOOR = 20.0  # m: orders are picked up and dropped anywhere in [0, FLOOR]^2
SHIFT = 600.0  # s of sim time per run


def scenario(
    seed: int,
    robots: int = 4,
    arrival_s: float = 8.0,
    dwell_s: float = 5.0,
    speed: float = 1.0,
):
    """One shift: the simulation and its main mission (the sweep's scenario function).

    Args:
        seed: Seeds the simulation's generator: order times and places.
        robots: Fleet size.
        arrival_s: Mean seconds between two orders.
        dwell_s: Seconds to load and to unload.
        speed: The robots' top speed in m/s.
    """
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, target_rtf=0.0, timestep=0.1, seed=seed, duration=SHIFT)
    )
    body = ShapeParams("box", half_extents=[0.3, 0.25, 0.1], rgba_color=[0.2, 0.4, 0.9, 1])
    fleet = [
        Agent.from_mesh(
            body,
            body,
            Pose.from_xyz(1.0 + 1.5 * i, -1.0, 0.1),
            sim_core=sim,
            name=f"robot{i}",
            controller={"type": "omni", "max_linear_vel": speed, "max_linear_accel": 1.0},
        )
        for i in range(robots)
    ]
    rng = sim.rng

    async def orders_arrive(orders: Store) -> None:
        number = 0
        while True:
            await sim.sleep(float(rng.exponential(arrival_s)))
            pickup, drop = rng.uniform(0.0, FLOOR, size=(2, 2)).tolist()
            await orders.put((number, Pose.from_xyz(*pickup, 0.1), Pose.from_xyz(*drop, 0.1)))
            number += 1

    async def serve(robot: Agent, orders: Store) -> None:
        while True:
            number, pickup, drop = await orders.get()
            try:
                await robot.move(pickup)
                await robot.wait(dwell_s)  # loading: busy, not moving (KPI "waiting")
                await robot.move(drop)
                await robot.wait(dwell_s)
            except ActionFailedError:
                sim.events.emit(SimEvents.TASK_FAILED, sim=sim, agent=robot, task=number)
            else:
                sim.events.emit(SimEvents.TASK_COMPLETED, sim=sim, agent=robot, task=number)

    async def main() -> None:
        orders = Store(sim)
        async with sim.task_group() as tg:
            tg.start_soon(orders_arrive, orders, name="orders")
            for robot in fleet:
                tg.start_soon(serve, robot, orders, name=robot.name)

    return sim, main


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=4)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--max-steps", type=int, default=int(SHIFT / 0.1), help="stop after this many steps"
    )
    args = parser.parse_args(argv)

    import fleet_async as fa

    sim, mission = scenario(args.seed, robots=args.robots)
    with sim:
        kpis = sim.kpis()
        fa.run(sim, mission, until=min(SHIFT, args.max_steps * sim.params.timestep))
        row = kpis.summary()
    print(
        f"{args.robots} robots, seed {args.seed}, {row.sim_time_s:.0f} s of sim time: "
        f"{row.tasks_completed} orders delivered ({row.throughput_per_hour:.1f} per hour), "
        f"{row.distance_total_m:.0f} m driven, {row.idle_time_mean_s:.0f} s idle and "
        f"{row.waiting_time_mean_s:.0f} s loading per robot, {row.collisions} collisions"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
