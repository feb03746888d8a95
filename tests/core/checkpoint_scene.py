"""A busy kinematic scene for the checkpoint tests, and a trace of how it continues.

Run as a script (``python checkpoint_scene.py restore CHECKPOINT STEPS``) it builds the scene
in a fresh process, restores the checkpoint and prints the trace's digest.
"""

from __future__ import annotations

import hashlib
import sys
from typing import Any

import numpy as np

from fleet_async import (
    Agent,
    AgentSpawnParams,
    DropAction,
    MoveAction,
    MultiRobotSimulationCore,
    PickAction,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    SimulationParams,
    WaitAction,
)

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
CRATE = ShapeParams("box", half_extents=[0.1, 0.1, 0.05])


def build(seed: int = 7) -> MultiRobotSimulationCore:
    """Differential and omni robots on random errands (from sim.rng, in a callback), one of
    them fetching a crate (pick, carry, drop), a patrol and a random walker, batteries."""
    sim = MultiRobotSimulationCore(
        SimulationParams(gui=False, target_rtf=0.0, timestep=0.1, seed=seed, enable_floor=False)
    )
    battery = [{"type": "battery", "config": {"drain_per_meter": 0.01}}]
    errands = []
    for i in range(4):
        kind = "differential" if i % 2 else "omni"
        params = AgentSpawnParams(
            visual_shape=BOX,
            collision_shape=BOX,
            initial_pose=Pose.from_xyz(0.0, 1.5 * i, 0.1),
            controller={"type": kind, "max_linear_vel": 1.5, "max_linear_accel": 2.0},
            name=f"errand{i}",
            plugins=battery,
        )
        errands.append(Agent.from_params(params, sim))
    crate = SimObject.from_mesh(CRATE, CRATE, Pose.from_xyz(4.0, -2.0, 0.05), sim_core=sim)
    crate.set_name("crate")
    carrier = Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(0.0, -2.0, 0.1), sim_core=sim, name="carrier", controller="omni"
    )
    carrier.add_action_sequence(
        [
            PickAction(target_object_id=crate, attach_relative_pose=Pose.from_xyz(0, 0, 0.2)),
            MoveAction(path=[Pose.from_xyz(2.0, -4.0, 0.1), Pose.from_xyz(-3.0, -4.0, 0.1)]),
            DropAction(drop_pose=Pose.from_xyz(-3.0, -5.0, 0.05)),
        ]
    )
    Agent.from_mesh(
        BOX,
        BOX,
        Pose.from_xyz(6.0, 6.0, 0.1),
        sim_core=sim,
        name="patrol",
        controller=[
            "omni",
            {"type": "patrol", "waypoints": [[6, 9, 0.1], [9, 9, 0.1]], "wait": 0.7},
        ],
    )
    Agent.from_mesh(
        BOX,
        BOX,
        Pose.from_xyz(-6.0, 6.0, 0.1),
        sim_core=sim,
        name="walker",
        controller=["differential", {"type": "random_walk", "radius": 3.0}],
    )

    def send_errands(sim: MultiRobotSimulationCore, dt: float) -> None:
        for robot in errands:
            if robot.is_action_queue_empty():
                x, y = sim.rng.uniform(-4.0, 4.0, size=2).tolist()
                robot.add_action(MoveAction(path=Pose.from_xyz(x, y, 0.1)))
                robot.add_action(WaitAction(duration=float(sim.rng.uniform(0.0, 1.5))))

    sim.register_callback(send_errands, frequency=2.0)
    return sim


def trace(sim: MultiRobotSimulationCore, steps: int) -> dict[str, Any]:
    """Poses every step, every action and collision event, batteries and the next random
    number, over ``steps`` steps."""
    events: list[tuple[Any, ...]] = []

    def on_action(event: str) -> Any:
        def handler(agent: Any, action: Any, **_: Any) -> None:
            events.append((sim.step_count, event, agent.name, type(action).__name__))

        return handler

    for event in (SimEvents.ACTION_STARTED, SimEvents.ACTION_COMPLETED, SimEvents.ACTION_FAILED):
        sim.events.on(event, on_action(event))
    for event in (SimEvents.COLLISION_STARTED, SimEvents.COLLISION_ENDED):
        sim.events.on(
            event,
            lambda obj_a, obj_b, event=event, **_: events.append(
                (sim.step_count, event, obj_a.name, obj_b.name)
            ),
        )
    ids = [obj.object_id for obj in sim.sim_objects]
    poses = []
    for _ in range(steps):
        sim.step_once()
        position, orientation = sim.get_poses(ids)
        poses.append(np.concatenate([position, orientation], axis=1))
    return {
        "poses": np.array(poses),
        "events": events,
        "step": sim.step_count,
        "collisions": sim.collision_count,
        "soc": [a.battery_soc for a in sim.agents],
        "rng": float(sim.rng.uniform()),
    }


def digest(result: dict[str, Any]) -> str:
    """One hash of everything in a trace (poses bit for bit)."""
    h = hashlib.sha256(result["poses"].tobytes())
    h.update(repr({k: v for k, v in result.items() if k != "poses"}).encode())
    return h.hexdigest()


if __name__ == "__main__":
    _, command, path, steps = sys.argv
    assert command == "restore"
    scene = build()
    scene.restore_state(path)
    print(digest(trace(scene, int(steps))))
