"""Hello, fleet: four carriers shuttle pallets from shelves to a packing station, headless.

Run:  python examples/hello_fleet.py [--max-steps N] [--gui]

Each carrier is a kinematic box moved by a 10 Hz sim-time callback (the agent controllers and
the action queue arrive with the agents issue). It drives to a pallet, attaches it, carries it
to the station, drops it, and the script prints what happened in sim time.
"""

from __future__ import annotations

import argparse

import numpy as np

from fleet_async import MultiRobotSimulationCore, Pose, ShapeParams, SimObject, SimulationParams

SPEED = 1.0  # m/s
STATION = np.array([0.0, -4.0, 0.1])


def spawn_box(sim, name, xyz, half, rgba, pickable=True):
    shape = ShapeParams("box", half_extents=half, rgba_color=rgba)
    return SimObject.from_mesh(
        shape, shape, Pose.from_xyz(*xyz), sim_core=sim, name=name, pickable=pickable
    )


class Shuttle:
    """Drive to the pallet, pick it, drive to the station, drop it."""

    def __init__(self, carrier, pallet, log):
        self.carrier, self.pallet, self.log = carrier, pallet, log
        self.stage = "to_pallet"

    def target(self):
        if self.stage == "to_pallet":
            return self.pallet.get_pose().position * np.array([1, 1, 0]) + np.array([0, 0, 0.1])
        return STATION + np.array([self.carrier.object_id * 0.6, 0, 0])

    def tick(self, sim, dt):
        if self.stage == "done":
            return
        here = self.carrier.get_pose().position
        delta = self.target() - here
        dist = float(np.linalg.norm(delta))
        if dist > SPEED * dt:
            self.carrier.set_pose(Pose(here + delta / dist * SPEED * dt))
            return
        self.carrier.set_pose(Pose(self.target()))
        if self.stage == "to_pallet":
            self.carrier.attach_object(self.pallet, relative_pose=Pose.from_xyz(0, 0, 0.2))
            self.log(sim, f"{self.carrier.name} picked {self.pallet.name}")
            self.stage = "to_station"
        else:
            self.carrier.detach_object(self.pallet, drop_relative_pose=Pose.from_xyz(0, 0, -0.1))
            self.log(sim, f"{self.carrier.name} dropped {self.pallet.name} at the station")
            self.stage = "done"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-steps", type=int, default=2000, help="stop after this many steps")
    parser.add_argument(
        "--gui", action="store_true", help="open the PyBullet window (needs a display)"
    )
    args = parser.parse_args(argv)

    params = SimulationParams(
        gui=args.gui, target_rtf=1.0 if args.gui else 0.0, monitor=False, timestep=0.1
    )
    with MultiRobotSimulationCore(params) as sim:
        shelves = SimObject.from_sdf("kiva_shelf/model.sdf", sim_core=sim, collision_mode="static")
        shelves[0].set_pose(Pose.from_xyz(0, 4, 0))

        def log(s, message):
            print(f"[t={s.sim_time:6.1f} s] {message}")

        shuttles = []
        for i in range(4):
            carrier = spawn_box(
                sim,
                f"carrier{i}",
                (-3 + 2 * i, 0, 0.1),
                [0.25, 0.25, 0.1],
                [0.2, 0.4, 0.9, 1],
                False,
            )
            pallet = spawn_box(
                sim, f"pallet{i}", (-3 + 2 * i, 3 + i, 0.1), [0.2, 0.2, 0.1], [0.8, 0.6, 0.3, 1]
            )
            shuttles.append(Shuttle(carrier, pallet, log))
        for shuttle in shuttles:
            sim.register_callback(shuttle.tick, frequency=10.0)

        while sim.step_count < args.max_steps and any(s.stage != "done" for s in shuttles):
            sim.step_once()

        delivered = sum(s.stage == "done" for s in shuttles)
        print(
            f"{delivered}/{len(shuttles)} pallets delivered in {sim.sim_time:.1f} s of sim time "
            f"({sim.step_count} steps, {len(sim.sim_objects)} objects)"
        )
    return 0 if delivered == len(shuttles) else 1


if __name__ == "__main__":
    raise SystemExit(main())
