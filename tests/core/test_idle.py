"""Idle-step skipping: ``sim.idle_steps`` / ``sim.skip_steps`` and the drivers that use them.

Every test runs one scenario twice, once with ``step_once()`` only and once skipping the
empty spans, and demands the same sim times, step counts, poses and event logs.
"""

from __future__ import annotations

import numpy as np
import pytest

from fleet_async import (
    Agent,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    SimPlugin,
    WaitAction,
)
from tests.conftest import headless_params

CUBE = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def robot(sim, x, y=0.0):
    return Agent.from_mesh(CUBE, CUBE, Pose.from_xyz(x, y, 0.1), sim_core=sim, controller="omni")


def run(sim, steps, skip):
    """Advance ``steps`` steps by stepping, or skipping empty spans; return the spans."""
    end = sim.step_count + steps
    spans = []
    while sim.step_count < end:
        free = sim.idle_steps(end - sim.step_count) if skip else 0
        if free:
            sim.skip_steps(free)
            spans.append(free)
        else:
            sim.step_once()
    return spans


def both(scenario, steps, **params):
    """Run ``scenario(sim, log)`` stepped and skipping; return both logs and the spans."""
    logs, spans = [], []
    for skip in (False, True):
        with MultiRobotSimulationCore(headless_params(enable_floor=False, **params)) as sim:
            log: list = []
            scenario(sim, log)
            spans.append(run(sim, steps, skip))
            log.append(("end", sim.step_count, sim.sim_time))
            logs.append(log)
    return logs[0], logs[1], spans[1]


def test_a_1_hz_callback_fires_at_the_same_sim_times():
    def scenario(sim, log):
        sim.register_callback(lambda s, dt: log.append(("cb", s.sim_time, dt)), frequency=1.0)

    stepped, skipped, spans = both(scenario, 95)
    assert stepped == skipped
    assert [entry[1] for entry in stepped[:-1]] == pytest.approx([float(t) for t in range(1, 10)])
    assert spans and sum(spans) > 80  # most of the run was skipped


def test_step_count_and_sim_time_after_a_span_equal_a_stepped_run():
    for skip in (False, True):
        with MultiRobotSimulationCore(headless_params()) as sim:
            robot(sim, 0.0)
            sim.step_once()
            run(sim, 37, skip)
            assert sim.step_count == 38
            assert sim.sim_time == 38 * 0.1  # the same float as stepping gives


def test_a_body_set_moving_from_a_callback_is_never_skipped_over():
    def scenario(sim, log):
        agent = robot(sim, 0.0)

        def start(s, dt):
            if not agent.is_moving:
                agent.set_goal_pose(Pose.from_xyz(agent.get_pose().x + 1.5, 0.0, 0.1))

        sim.register_callback(start, frequency=0.25)  # every 4 s
        sim.register_callback(
            lambda s, dt: log.append(("pose", s.sim_time, *agent.get_pose().position)),
            frequency=2.0,
        )

    stepped, skipped, spans = both(scenario, 200)
    assert stepped == skipped
    assert stepped[-2][2] == pytest.approx(6.0)  # it moved 1.5 m four times
    assert spans  # and the waits between moves were skipped


def test_collision_events_are_identical():
    def scenario(sim, log):
        robot(sim, 0.0)
        b = robot(sim, 3.0)
        for event in (SimEvents.COLLISION_STARTED, SimEvents.COLLISION_ENDED):
            sim.events.on(
                event,
                lambda obj_a, obj_b, e=event, **_: log.append(
                    (e, round(sim.sim_time, 9), obj_a.object_id, obj_b.object_id)
                ),
            )

        def shuffle(s, dt):
            k = round(s.sim_time)
            if k % 3 == 0:
                b.set_goal_pose(Pose.from_xyz(0.5 if k % 2 else 3.0, 0.0, 0.1))
            elif k % 5 == 0:
                b.set_pose(Pose.from_xyz(0.15, 0.0, 0.1))  # a teleport into contact

        sim.register_callback(shuffle, frequency=1.0)

    stepped, skipped, spans = both(scenario, 300)
    assert stepped == skipped
    assert sum(1 for e in stepped if e[0] == SimEvents.COLLISION_STARTED) >= 2
    assert spans


def test_collision_checks_at_a_frequency_keep_their_schedule():
    def scenario(sim, log):
        SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(0, 0, 0.1), sim_core=sim)
        b = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(3, 0, 0.1), sim_core=sim)
        sim.events.on(
            SimEvents.COLLISION_STARTED,
            lambda **_: log.append(("started", round(sim.sim_time, 9))),
        )
        # Teleports between checks (checks every 0.7 s = 7 steps) land at different phases.
        moves = {1.3: 0.15, 2.9: 3.0, 4.1: 0.1, 6.0: 3.0, 8.8: 0.19}

        def teleport(s, dt):
            for when, x in moves.items():
                if abs(s.sim_time - when) < 1e-6:
                    b.set_pose(Pose.from_xyz(x, 0, 0.1))

        sim.register_callback(teleport, frequency=10.0 / 3)  # fires every ~0.3 s

    stepped, skipped, _ = both(scenario, 120, collision_check_frequency=1 / 0.7)
    assert stepped == skipped


def test_plugins_object_callbacks_and_wait_actions_keep_exact_times():
    class Beacon(SimPlugin):
        def on_step(self, dt):
            self.sim_core.events.emit("beacon", t=self.sim_core.sim_time)

    def scenario(sim, log):
        sim.register_plugin(Beacon, frequency=0.3)
        sim.events.on("beacon", lambda t: log.append(("beacon", round(t, 9))))
        agent = robot(sim, 0.0)
        agent.register_callback(lambda obj, dt: log.append(("obj", round(sim.sim_time, 9))), 0.7)
        for d in (2.35, 0.0, 4.0):
            agent.add_action(WaitAction(duration=d))
        sim.events.on(
            SimEvents.ACTION_COMPLETED,
            lambda agent, action: log.append(("done", round(action.end_time, 9))),
        )

    stepped, skipped, spans = both(scenario, 150)
    assert stepped == skipped
    assert [e[1] for e in stepped if e[0] == "done"] == pytest.approx([2.4, 2.4, 6.4])
    assert spans


def test_what_keeps_steps_from_being_skipped(sim):
    agent = robot(sim, 0.0)
    assert sim.idle_steps(10) == 0  # not initialised: the first step runs
    sim.step_once()
    assert sim.idle_steps(10) == 10
    agent.set_goal_pose(Pose.from_xyz(1.0, 0.0, 0.1))
    assert sim.idle_steps(10) == 0  # a body is moving
    with pytest.raises(ValueError, match="not provably empty"):
        sim.skip_steps(3)
    while agent.is_moving:
        sim.step_once()
    sim.step_once()  # the arrival's velocity is zeroed by the next step
    assert sim.idle_steps(10) == 10
    handler = sim.events.on(SimEvents.POST_STEP, lambda **_: None)
    assert sim.idle_steps(10) == 0  # someone listens to every step
    sim.events.off(SimEvents.POST_STEP, handler)

    def every_step(s, dt):
        pass

    sim.register_callback(every_step)
    assert sim.idle_steps(10) == 0
    sim.unregister_callback(every_step)
    assert sim.idle_steps(10) == 10
    sim.pause()
    assert sim.idle_steps(10) == 0


def test_a_pose_write_needs_one_real_step_for_its_collision_check(sim):
    a = SimObject.from_mesh(CUBE, CUBE, Pose.from_xyz(0, 0, 0.1), sim_core=sim)
    sim.step_once()
    assert sim.idle_steps(5) == 5
    a.set_pose(Pose.from_xyz(1, 0, 0.1))
    assert sim.idle_steps(5) == 0
    sim.step_once()
    assert sim.idle_steps(5) == 5


def test_skip_steps_emits_the_span_and_step_once_is_one_step(sim):
    robot(sim, 0.0)
    spans = []
    sim.events.on(SimEvents.STEPS_SKIPPED, lambda **kw: spans.append(kw))
    sim.step_once()
    sim.skip_steps(sim.idle_steps(25))
    assert spans == [{"sim": sim, "step": 1, "count": 25, "sim_time": sim.sim_time}]
    sim.step_once()
    assert sim.step_count == 27
    sim.skip_steps(0)
    with pytest.raises(ValueError, match="not provably empty"):
        sim.skip_steps(-1)


def _goal_chaser(fast):
    with MultiRobotSimulationCore(headless_params(enable_floor=False)) as sim:
        agent = robot(sim, 0.0)
        calls = []
        sim.register_callback(lambda s, dt: calls.append(s.sim_time), frequency=0.5)
        sim.register_callback(
            lambda s, dt: agent.set_goal_pose(Pose.from_xyz(s.sim_time, 1.0, 0.1)),
            frequency=0.2,
        )
        if fast:
            sim.run_simulation(duration=30.0)
        else:
            for _ in range(300):
                sim.step_once()
        return sim.step_count, calls, agent.get_pose().position.tolist()


def test_run_simulation_skips_and_lands_on_the_same_state():
    stepped, skipped = _goal_chaser(False), _goal_chaser(True)
    assert stepped == skipped
    assert np.allclose(stepped[2], [25.0, 1.0, 0.1])
