"""Commands are recorded in the trace with their step; replaying them reproduces the run.

A run mixes what drives robots: two served vehicles take orders from a "master" that sends
them at wall-clock moments (here: at chosen steps, from a step observer), and a mission drives
a third robot. The replay builds the same simulation, takes the commands from the trace alone,
and must give the same poses at every step (float64, bit for bit) and the same events, on
asyncio and on trio.
"""

from __future__ import annotations

import numpy as np
import pytest

from fleet_async import Agent, MultiRobotSimulationCore, Pose, ShapeParams, SimObject, run
from fleet_async.interfaces import (
    Edge,
    FleetInterface,
    InstantTasks,
    Node,
    Order,
    Task,
    replay_commands,
)
from fleet_async.tasks import ExternallyDrivenError
from fleet_async.viewer import TraceReader
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
SMALL = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])
BACKENDS = ["asyncio", "trio"]


def build() -> MultiRobotSimulationCore:
    sim = MultiRobotSimulationCore(headless_params())
    for i, controller in enumerate(("omni", "differential", "omni")):
        Agent.from_mesh(
            BOX,
            BOX,
            Pose.from_xyz(0.0, 3.0 * i, 0.1),
            sim_core=sim,
            controller=controller,
            name=f"r{i}",
        )
    SimObject.from_mesh(SMALL, SMALL, Pose.from_xyz(3.0, 0.0, 0.1), sim_core=sim, name="tote")
    return sim


def line(order_id: str, y: float, xs: list[float], released: int, update: int = 0, first: int = 0):
    nodes = tuple(
        Node(f"n{first + i}", 2 * (first + i), i < released, x, y) for i, x in enumerate(xs)
    )
    edges = tuple(
        Edge(
            f"e{first + i}",
            2 * (first + i) + 1,
            f"n{first + i}",
            f"n{first + i + 1}",
            released=i + 1 < released,
        )
        for i in range(len(xs) - 1)
    )
    return Order(order_id, update, nodes, edges)


PICK = Task("pick", "pick1", params={"load_id": "tote"})
SCRIPT = {
    3: [("r0", line("a", 0.0, [0.0, 3.0, 6.0, 9.0], released=3))],
    7: [("r1", line("b", 3.0, [0.0, 4.0], released=2))],
    20: [("r1", InstantTasks((Task("cancel_order", "c1"),)))],
    40: [("r0", InstantTasks((Task("start_pause", "p1"),)))],
    55: [("r0", InstantTasks((Task("stop_pause", "p2"),)))],
    120: [("r0", line("a", 0.0, [6.0, 9.0], released=2, update=1, first=2))],
}


async def mission(sim: MultiRobotSimulationCore) -> None:
    r2 = next(a for a in sim.agents if a.name == "r2")
    await r2.move(Pose.from_xyz(5.0, 6.0, 0.1))
    await sim.sleep(2.0)
    await r2.move(Pose.from_xyz(0.0, 6.0, 0.1))
    await sim.sleep_until(30.0)  # the run lasts 30 s: the master speaks until then


def record_poses(sim: MultiRobotSimulationCore, poses: list[np.ndarray]) -> None:
    def observe(step: int) -> None:
        poses.append(np.array([a.get_pose().position for a in sim.agents]))

    sim.add_step_observer(observe)


def live_run(tmp_path, backend: str) -> tuple[list[np.ndarray], str]:
    sim = build()
    fleet = FleetInterface(sim, ["r0", "r1"], visualization_period=0)
    poses: list[np.ndarray] = []
    record_poses(sim, poses)

    def master(step: int) -> None:  # speaks after step ``step``: applied before the next
        for name, command in SCRIPT.get(step, ()):
            fleet.submit(name, command)

    sim.add_step_observer(master)
    path = str(tmp_path / f"live_{backend}.fatrace")
    sim.start_trace(path)
    run(sim, mission, sim, backend=backend)
    sim.stop_trace()
    sim.close()
    return poses, path


@pytest.mark.parametrize("backend", BACKENDS)
def test_replaying_the_traced_commands_reproduces_the_run(tmp_path, backend):
    poses, path = live_run(tmp_path, backend)
    live = TraceReader(path)
    assert [(c["step"], c["vehicle"]) for c in live.commands] == [
        (step, name) for step, items in sorted(SCRIPT.items()) for name, _ in items
    ]
    sim = build()
    replay_commands(sim, path, ["r0", "r1"])
    again: list[np.ndarray] = []
    record_poses(sim, again)
    replayed_path = str(tmp_path / "replayed.fatrace")
    sim.start_trace(replayed_path)
    run(sim, mission, sim, backend=backend)
    sim.stop_trace()
    sim.close()
    assert len(again) == len(poses) == 300
    assert all(np.array_equal(a, b) for a, b in zip(poses, again, strict=True))
    replayed = TraceReader(replayed_path)
    assert replayed.events == live.events and replayed.commands == live.commands
    states = [e for e in live.events if e["kind"] == "vehicle_state"]
    first = states[0]["data"]
    assert (states[0]["step"], first["vehicle"], first["order_id"]) == (4, "r0", "a")
    assert first["nodes"] == [["n1", 2, True, 3.0, 0.0], ["n2", 4, True, 6.0, 0.0],
                              ["n3", 6, False, 9.0, 0.0]]  # fmt: skip
    # The run did what the script asked: r0 paused, resumed, was updated and reached x = 9.
    assert poses[-1][0][0] == pytest.approx(9.0, abs=1e-9)
    assert 0.0 < poses[-1][1][0] < 4.0  # r1 was cancelled on its way
    assert poses[-1][2][:2] == pytest.approx([0.0, 6.0], abs=1e-9)


def test_the_run_is_the_same_on_asyncio_and_trio(tmp_path):
    on_asyncio, _ = live_run(tmp_path, "asyncio")
    on_trio, _ = live_run(tmp_path, "trio")
    assert all(np.array_equal(a, b) for a, b in zip(on_asyncio, on_trio, strict=True))


def test_a_mission_cannot_command_a_served_robot():
    sim = build()
    FleetInterface(sim, ["r0"])

    async def meddle(sim: MultiRobotSimulationCore) -> None:
        r0 = next(a for a in sim.agents if a.name == "r0")
        await r0.move(Pose.from_xyz(1.0, 0.0, 0.1))

    with pytest.raises(ExternallyDrivenError, match="'r0' is driven by a fleet master"):
        run(sim, meddle, sim)
    sim.close()


def test_closing_the_interface_gives_the_robot_back_to_missions():
    sim = build()
    fleet = FleetInterface(sim, ["r0"])
    fleet.close()

    async def drive(sim: MultiRobotSimulationCore) -> None:
        r0 = next(a for a in sim.agents if a.name == "r0")
        await r0.move(Pose.from_xyz(1.0, 0.0, 0.1))

    run(sim, drive, sim)
    assert sim.agents[0].get_pose().x == pytest.approx(1.0)
    sim.close()
