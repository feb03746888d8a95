"""Two fixed arms move boxes from one table to another, headless.

Run:  python examples/arm_pick_place.py [--max-steps N] [--gui]

A Franka Panda (from pybullet_data) and the project's 4-joint arm_robot each stand between two
tables. Each arm picks three boxes off its left table and places them on its right table: the
pick and drop actions reach with inverse kinematics (``ee_target_position``) and attach the box
to the end-effector link (or set it down); the arm stays where each reach took it until the next
one. The script prints every action as it ends, in sim time, and checks where the boxes ended up.
"""

from __future__ import annotations

import argparse
import math

import pybullet as p

from fleet_async import (
    Agent,
    DropAction,
    MultiRobotSimulationCore,
    PickAction,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    SimulationParams,
)

TABLE = ShapeParams("box", half_extents=[0.15, 0.15, 0.1], rgba_color=[0.55, 0.4, 0.25, 1])
BOX = ShapeParams("box", half_extents=[0.025, 0.025, 0.025], rgba_color=[0.9, 0.2, 0.2, 1])
DOWN = p.getQuaternionFromEuler([math.pi, 0.0, 0.0])  # gripper pointing at the floor

# name, model, base position, end-effector link, tool orientation, table x offsets
CELLS = [
    ("panda", "panda", (0.0, 0.0), "panda_grasptarget", DOWN),
    ("arm_robot", "arm_robot", (0.0, 2.0), "end_effector", None),
]


def build_cell(sim, name, model, base, ee_link, orientation):
    """One arm, a table on each side and three boxes on the left table; returns the work."""
    bx, by = base
    arm = Agent.from_urdf(
        model, pose=Pose([bx, by, 0.0]), use_fixed_base=True, sim_core=sim, name=name
    )
    for side in (-1, 1):
        SimObject.from_mesh(
            TABLE,
            TABLE,
            Pose([bx + 0.3, by + 0.3 * side, 0.1]),
            sim_core=sim,
            pickable=False,
            collision_mode="static",
        )
    actions = []
    for k in range(3):
        x = bx + 0.22 + 0.08 * k
        box = SimObject.from_mesh(
            BOX, BOX, Pose([x, by - 0.3, 0.225]), sim_core=sim, name=f"{name}_box{k}"
        )
        grasp = [x, by - 0.3, 0.26]  # just above the box
        place = [x, by + 0.3, 0.26]
        actions.append(
            (
                box,
                PickAction(
                    target_object_id=box.body_id,
                    ee_target_position=grasp,
                    ee_target_orientation=orientation,
                    ee_end_effector_link=ee_link,
                    attach_link=ee_link,
                    attach_relative_pose=Pose([0.0, 0.0, 0.0]),
                    continue_on_ik_failure=False,
                ),
                DropAction(
                    drop_pose=Pose([x, by + 0.3, 0.225]),
                    ee_target_position=place,
                    ee_target_orientation=orientation,
                    ee_end_effector_link=ee_link,
                    continue_on_ik_failure=False,
                ),
            )
        )
    for _, pick, drop in actions:
        arm.add_action_sequence([pick, drop])
    return arm, actions


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-steps", type=int, default=3000, help="stop after this many steps")
    parser.add_argument(
        "--gui", action="store_true", help="open the PyBullet window (needs a display)"
    )
    args = parser.parse_args(argv)
    params = SimulationParams(
        gui=args.gui, target_rtf=1.0 if args.gui else 0.0, monitor=False, timestep=0.05
    )
    with MultiRobotSimulationCore(params) as sim:
        cells = [build_cell(sim, *cell) for cell in CELLS]
        failed = []

        def report(outcome):
            def handler(agent, action):
                if outcome == "failed":
                    failed.append(action)
                detail = f": {action.error_message}" if action.error_message else ""
                print(
                    f"[t={action.end_time:5.2f} s] {agent.name} {outcome} "
                    f"{type(action).__name__}{detail}"
                )

            return handler

        sim.events.on(SimEvents.ACTION_COMPLETED, report("completed"))
        sim.events.on(SimEvents.ACTION_FAILED, report("failed"))
        arms = [arm for arm, _ in cells]
        while sim.step_count < args.max_steps and not all(a.is_action_queue_empty() for a in arms):
            sim.step_once()

        placed = 0
        for _, work in cells:
            for box, _, drop in work:
                target = drop.drop_pose.position
                off = float(((box.get_pose().position - target) ** 2).sum() ** 0.5)
                placed += int(not box.is_attached() and off < 1e-6)
        total = sum(len(work) for _, work in cells)
        print(
            f"{placed}/{total} boxes placed on the far tables in {sim.sim_time:.2f} s of sim "
            f"time ({sim.step_count} steps), {len(failed)} actions failed"
        )
    return 0 if placed == total and not failed else 1


if __name__ == "__main__":
    raise SystemExit(main())
