"""Safety fields hold velocity commands too (gap (a) of issue 29), and a custom base
controller, which moves its robot itself, is not watched."""

from __future__ import annotations

import pytest

from fleet_async import Pose, SimEvents
from fleet_async.core.motion.controllers import OmniController
from tests.core.traffic.test_safety_fields import make_sim, record, robot, wall


def test_a_velocity_command_stops_at_a_wall_and_resumes_when_it_is_cleared():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a", fields={"warning_margin": 0.0})
        w = wall(sim, 3.0)
        log = record(sim)
        a.set_cmd_vel(vx=1.0)
        xs = []
        for _ in range(60):  # stop, creep (its field shrinks to standstill depth), stop
            sim.step_once()
            xs.append(a.get_pose().x)
        assert sim.safety.is_stopped(a)
        assert a.is_moving  # the command stays in force while the robot is stopped
        assert float(a.velocity[0]) == 0.0
        front = a.get_pose().x + 0.3
        assert 0.0 <= 2.7 - front <= 0.1 + 1e-9  # within its standstill protective depth
        assert xs[-1] == xs[-15]  # standing
        assert log[0][0] == "start" and log[0][3] == ["wall"]
        sim.remove_object(w)
        for _ in range(20):
            sim.step_once()
        assert not sim.safety.is_stopped(a)
        assert a.get_pose().x > xs[-1] + 1.0  # drove on
        assert log[-1][0] == "end" and log[-1][1] == 60  # the first step after the wall left


def test_without_fields_the_same_command_drives_through_the_wall():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a", fields=None)
        wall(sim, 3.0)
        a.set_cmd_vel(vx=1.0)
        for _ in range(40):
            sim.step_once()
        assert a.get_pose().x > 3.0


def test_the_warning_field_caps_a_velocity_command_at_its_slow_factor():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a", fields={"warning_margin": 3.0, "slow_factor": 0.25})
        wall(sim, 5.0)
        a.set_cmd_vel(vx=1.0)
        speeds = []
        for _ in range(25):
            sim.step_once()
            speeds.append(float(a.velocity[0]))
        assert max(speeds) == pytest.approx(1.0)  # before the wall is in the warning field
        assert speeds[-5:] == pytest.approx([0.25] * 5)  # then at its slow factor
        assert not sim.safety.is_stopped(a)


class _Teleport(OmniController):
    """A custom base controller: it moves its robot itself, 1 m/s along x."""

    def compute(self, agent, dt):
        pose = agent.get_pose()
        agent.set_pose(Pose.from_xyz(pose.x + dt, pose.y, pose.z))


def test_a_custom_base_controller_is_not_held():
    with make_sim() as sim:
        a = robot(sim, 0.0, name="a")
        a.set_controller(_Teleport())
        wall(sim, 3.0)
        stops = []
        sim.events.on(SimEvents.SAFETY_STOP_STARTED, lambda agent, **_: stops.append(agent))
        for _ in range(40):
            sim.step_once()
        assert a.get_pose().x == pytest.approx(4.0)
        assert stops == []
