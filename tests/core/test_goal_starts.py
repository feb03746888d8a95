"""Goals started in one batch (``KinematicEngine.start_goals``, what the fleet does for the
goals of patrols and random walks that come due together) against ``set_path([goal])`` one
agent at a time: the segment columns, plans and modes must be equal bit for bit, for every
kind of goal (plain straight moves, goals the batch hands back: differential robots, turned or
unnormalised orientations, goals where the robot stands, per-axis limits, moving robots), and
a fleet of patrols and random walks must run the same trace either way."""

from __future__ import annotations

import numpy as np
import pytest

from fleet_async import Agent, AgentSpawnParams, MultiRobotSimulationCore, Pose, ShapeParams
from fleet_async.core.motion.controllers import PatrolController
from fleet_async.core.motion.goal_starts import BATCH_MIN
from fleet_async.core.motion.slots import SEGMENT_COLUMNS
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def _fleet(seed: int) -> tuple[MultiRobotSimulationCore, list[Agent], list[Pose]]:
    """96 robots of every kind the batch sees, and one goal each (seeded)."""
    rng = np.random.default_rng(seed)
    sim = MultiRobotSimulationCore(headless_params(enable_floor=False))
    agents, goals = [], []
    for i in range(96):
        case = i % 8
        controller: dict[str, object] = {"type": "omni"}
        if case == 1:
            controller = {"type": "differential"}
        elif case == 2:
            controller = {"type": "omni", "max_linear_vel": [1.0, 0.5, 0.2]}
        elif case == 3:
            controller = {"type": "omni", "max_linear_accel": float("inf")}
        yaw = float(rng.uniform(-3.0, 3.0)) if case == 4 else 0.0
        x0, y0 = float(rng.uniform(0, 20)), float(rng.uniform(0, 20))
        start = Pose.from_euler(x0, y0, 0.1, 0.0, 0.0, yaw)
        agent = Agent.from_params(
            AgentSpawnParams(
                visual_shape=None,
                collision_shape=BOX,
                initial_pose=start,
                controller=[controller],
            ),
            sim_core=sim,
        )
        x, y = float(rng.uniform(0, 20)), float(rng.uniform(0, 20))
        goal = Pose.from_euler(x, y, 0.1, 0.0, 0.0, float(rng.uniform(-3.0, 3.0)))
        if case == 5:  # where it stands
            goal = Pose(start.position.copy(), goal.orientation)
        if case == 6:  # already moving: the batch hands it back
            agent.set_path([Pose.from_xyz(x + 1.0, y, 0.1)])
        agents.append(agent)
        goals.append(goal)
    sim.step_once()
    return sim, agents, goals


def _state(sim: MultiRobotSimulationCore) -> tuple[object, ...]:
    engine = sim.fleet.engine
    high = engine._high
    plans = [
        None
        if plan is None
        else (
            [(w.position.tobytes(), w.orientation.tobytes()) for w in plan.waypoints],
            plan.direction,
            plan.final_align,
            plan.final_orientation.tobytes(),
            plan.total,
            plan.stage,
            plan.aligned,
        )
        for plan in engine._plans[:high]
    ]
    columns = {name: getattr(engine, name)[:high].tobytes() for name in SEGMENT_COLUMNS}
    return engine.mode[:high].tobytes(), plans, columns


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_start_goals_matches_set_path_bit_for_bit(seed: int) -> None:
    one, agents_one, goals = _fleet(seed)
    batch, agents_batch, _ = _fleet(seed)
    with one, batch:
        for agent, goal in zip(agents_one, goals, strict=True):
            agent.set_path([goal])
        engine = batch.fleet.engine
        slots = [a.motion_slot for a in agents_batch]
        handed_back: list[int] = []
        one_by_one = engine.set_path

        def recorded(slot: int, *args: object) -> None:
            handed_back.append(slots.index(slot))
            one_by_one(slot, *args)  # type: ignore[arg-type]

        engine.set_path = recorded  # type: ignore[method-assign]
        assert len(slots) >= BATCH_MIN
        engine.start_goals(
            slots, goals, [a.controller_params.default_direction for a in agents_batch]
        )
        engine.set_path = one_by_one  # type: ignore[method-assign]
        assert _state(batch) == _state(one)
        # the plain omni robots went in the batch; differential, per-axis limits, unbounded
        # acceleration, no distance to go and moving robots came back (a turned robot goes
        # in the batch when its quaternion's squared norm is 1.0 to the bit, else back)
        assert {k % 8 for k in handed_back} >= {1, 2, 3, 5, 6}
        assert not {k for k in range(96) if k % 8 in (0, 7)} & set(handed_back)
        for _ in range(60):
            one.step_once()
            batch.step_once()
            assert one.state.position.tobytes() == batch.state.position.tobytes()
            assert one.state.orientation.tobytes() == batch.state.orientation.tobytes()
        assert [a.motion_result for a in agents_batch] == [a.motion_result for a in agents_one]


def _walkers(reference: bool, batches: list[int] | None = None) -> list[bytes]:
    """Patrols and random walks that start and stop together, stepped with their goals sent
    in batches (their sizes appended to ``batches``), or polled one by one (the per-robot
    reference path)."""
    sim = MultiRobotSimulationCore(headless_params(enable_floor=False, seed=7))
    with sim:
        for i in range(200):
            x, y = 3.0 * (i % 20), 3.0 * (i // 20)
            chain: list[dict[str, object]] = [{"type": "omni", "max_linear_vel": 1.5}]
            if i % 2:
                square = [[x + 1, y, 0.1], [x + 1, y + 1, 0.1], [x, y + 1, 0.1], [x, y, 0.1]]
                chain.append({"type": "patrol", "waypoints": square, "wait": 0.5})
            else:
                chain.append({"type": "random_walk", "radius": 1.0, "wait_range": [0.0, 1.0]})
            Agent.from_params(
                AgentSpawnParams(
                    visual_shape=None,
                    collision_shape=BOX,
                    initial_pose=Pose.from_xyz(x, y, 0.1),
                    controller=chain,
                ),
                sim_core=sim,
            )
        sim.fleet.reference_path = reference
        engine = sim.fleet.engine
        start_goals = engine.start_goals

        def counted(slots: list[int], *args: object) -> None:
            if batches is not None:
                batches.append(len(slots))
            start_goals(slots, *args)  # type: ignore[arg-type]

        engine.start_goals = counted  # type: ignore[method-assign]
        trace = []
        for _ in range(150):
            sim.step_once()
            trace.append(sim.state.position.tobytes() + sim.state.orientation.tobytes())
    return trace


def test_batched_goals_run_the_reference_trace() -> None:
    batches: list[int] = []
    assert _walkers(reference=False, batches=batches) == _walkers(reference=True)
    assert max(batches) >= BATCH_MIN  # the patrols' goals went together
    reference: list[int] = []
    _walkers(reference=True, batches=reference)
    assert not reference  # the reference path sends each goal on its own


class _Polite(PatrolController):
    """Skips a spot another robot is heading to: a decision that reads the other robots."""

    def next_goal(self, agent, now):
        goal = super().next_goal(agent, now)
        if goal is None:
            return None
        taken = [o.goal_pose for o in agent.sim_core.agents if o is not agent and o.goal_pose]
        for spot in (goal, Pose.from_xyz(0.0, 5.0, 0.1), Pose.from_xyz(5.0, 5.0, 0.1)):
            if not any(np.array_equal(t.position, spot.position) for t in taken):
                return spot
        return None


class _Logged(Agent):
    """Counts its motion commands (an agent class that overrides them, to log or veto)."""

    def set_path(self, path, *args, **kwargs):
        self.user_data["calls"] = self.user_data.get("calls", 0) + 1
        super().set_path(path, *args, **kwargs)


def _overrides(reference: bool) -> tuple[list, list[int], bytes]:
    """20 robots with patrols that read each other (first half) and on an agent class of
    their own (second half), started together."""
    sim = MultiRobotSimulationCore(headless_params(enable_floor=False))
    with sim:
        agents = []
        for i in range(40):
            pose = Pose.from_xyz(0.0, 0.25 * i, 0.1)
            if i < 20:
                agent = Agent.from_params(
                    AgentSpawnParams(
                        visual_shape=None,
                        collision_shape=BOX,
                        initial_pose=pose,
                        controller=[{"type": "omni"}],
                    ),
                    sim_core=sim,
                )
                agent.add_controller(_Polite(waypoints=[[5.0, 0.0, 0.1]], wait=0.0))
            else:
                patrol = {
                    "type": "patrol",
                    "waypoints": [[3.0, 0.25 * i, 0.1], [0.0, 0.25 * i, 0.1]],
                }
                agent = _Logged.from_params(
                    AgentSpawnParams(
                        visual_shape=None,
                        collision_shape=BOX,
                        initial_pose=pose,
                        controller=[{"type": "omni"}, patrol],
                    ),
                    sim_core=sim,
                )
            agents.append(agent)
        sim.fleet.reference_path = reference
        sim.step_once()
        goals = [None if a.goal_pose is None else a.goal_pose.position.tolist() for a in agents]
        for _ in range(60):
            sim.step_once()
        calls = [a.user_data.get("calls", 0) for a in agents[20:]]
        return goals, calls, sim.state.position.tobytes()


def test_controllers_and_agents_that_override_their_methods_run_one_by_one():
    batched, reference = _overrides(reference=False), _overrides(reference=True)
    assert batched == reference
    goals, calls, _ = batched
    assert goals[1] == [0.0, 5.0, 0.1]  # the second robot saw the first one's goal
    assert min(calls) > 1  # every patrol leg went through the agent's own set_path
