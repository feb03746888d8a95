"""Scenario functions the sweep tests run (loaded by file path, so any worker can load them)."""

from __future__ import annotations

from pathlib import Path

from fleet_async import (
    Agent,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimulationParams,
)

HERE = Path(__file__).resolve()
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def ref(name: str) -> str:
    """``"<this file>:name"``, the reference a FunctionScenario loads in its workers."""
    return f"{HERE}:{name}"


def random_fleet(seed: int, robots: int = 2, fail_at: int = -1):
    """Robots drive to random goals (from the seed) as missions, reporting a task each time.

    ``robots == fail_at`` raises while building, to test a failing run.
    """
    if robots == fail_at:
        raise ValueError(f"no fleet of {robots} today")
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, target_rtf=0.0, timestep=0.1, seed=seed, duration=20.0)
    )
    fleet = [
        Agent.from_mesh(
            BOX,
            BOX,
            Pose.from_xyz(2.0 * i, 0.0, 0.1),
            sim_core=sim,
            name=f"r{i}",
            controller={"type": "omni", "max_linear_vel": 2.0},
        )
        for i in range(robots)
    ]

    async def drive(robot: Agent) -> None:
        while True:
            x, y = sim.rng.uniform(-5.0, 5.0, size=2).tolist()
            await robot.move(Pose.from_xyz(x, y, 0.1))
            await robot.wait(1.0)
            sim.events.emit(SimEvents.TASK_COMPLETED, sim=sim, agent=robot, task=None)

    async def main() -> None:
        async with sim.task_group() as tg:
            for robot in fleet:
                tg.start_soon(drive, robot)

    return sim, main


def steps_only(seed: int, speed: float = 1.0):
    """No mission: one robot with a queued move; the sweep steps it for its duration."""
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, target_rtf=0.0, timestep=0.1, seed=seed, duration=5.0)
    )
    robot = Agent.from_mesh(
        BOX,
        BOX,
        Pose.from_xyz(0, 0, 0.1),
        sim_core=sim,
        controller={"type": "omni", "max_linear_vel": speed},
    )
    robot.set_goal_pose(Pose.from_xyz(float(seed % 3) + 1.0, 0.0, 0.1))
    return sim


def not_a_sim(seed: int):
    """Returns something that is not a simulation."""
    return {"seed": seed}


def walkers(seed: int, robots: int = 3):
    """Robots on random walks: their controllers draw from their own streams (sim.rng_for)."""
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, target_rtf=0.0, timestep=0.1, seed=seed, duration=10.0)
    )
    for i in range(robots):
        Agent.from_mesh(
            BOX,
            BOX,
            Pose.from_xyz(3.0 * i, 0.0, 0.1),
            sim_core=sim,
            name=f"w{i}",
            controller=["omni", {"type": "random_walk", "radius": 4.0}],
        )
    return sim
