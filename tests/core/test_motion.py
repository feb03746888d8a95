"""Motion guarantees of the built-in controllers, checked step by step with numbers."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from fleet_async import Agent, MoveAction, MultiRobotSimulationCore, Path, Pose, ShapeParams
from tests.conftest import headless_params

DT = 0.1
TOL = 1e-9
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def spawn(sim, controller="omni", xyz=(0.0, 0.0, 0.1), yaw=0.0, **kw):
    return Agent.from_mesh(
        BOX, BOX, Pose.from_euler(*xyz, yaw=yaw), sim_core=sim, controller=controller, **kw
    )


def run(sim, agent, max_steps=2000):
    """Step until the agent stops; return per-step (position, yaw, velocity, yaw rate)."""
    trace = []
    for _ in range(max_steps):
        sim.step_once()
        pose = agent.get_pose()
        trace.append((pose.position.copy(), pose.yaw, agent.velocity, agent.angular_velocity))
        if not agent.is_moving:
            return trace
    raise AssertionError("agent did not stop")


def accelerations(values):
    v = np.vstack([np.zeros_like(values[0]), *values, np.zeros_like(values[0])])
    return np.diff(v, axis=0) / DT


def test_omni_trapezoid_reaches_goal_exactly_within_limits(sim):
    agent = spawn(sim, {"type": "omni", "max_linear_vel": 2.0, "max_linear_accel": 5.0})
    agent.set_goal_pose(Pose.from_xyz(10.0, 0.0, 0.1))
    trace = run(sim, agent)
    assert agent.get_pose().position.tolist() == [10.0, 0.0, 0.1]
    speeds = np.array([np.linalg.norm(v) for _, _, v, _ in trace])
    assert speeds.max() <= 2.0 + TOL
    assert np.abs(accelerations(list(speeds[:, None]))).max() <= 5.0 + 1e-6
    # The exact trapezoid, sampled each step: 0.4 s (4 steps, 0.4 m) accelerating at 5 m/s^2,
    # so the mean speeds of those steps are 0.25, 0.75, 1.25, 1.75 m/s; cruise at 2.0 m/s for
    # 9.2 m (46 steps), then brake symmetrically: 54 steps (5.4 s), ending exactly on the goal.
    # The first step moves a * dt^2 / 2 = 0.025 m, the most a start from rest allows.
    assert trace[0][0][0] == pytest.approx(0.025)
    assert speeds[:5] == pytest.approx([0.25, 0.75, 1.25, 1.75, 2.0])
    assert speeds[-5:] == pytest.approx([2.0, 1.75, 1.25, 0.75, 0.25])
    assert len(trace) == 54 and np.isclose(speeds, 2.0).sum() == 46
    assert agent.motion_result is True
    assert agent.velocity[0] == pytest.approx(0.25)  # the arrival step's own velocity
    sim.step_once()
    assert agent.velocity.tolist() == [0.0, 0.0, 0.0]


@pytest.mark.parametrize("seed", range(5))
def test_limits_hold_every_step_on_random_paths(sim, seed):
    rng = np.random.default_rng(seed)
    limits = {
        "max_linear_vel": [1.0, 0.5, 0.3],
        "max_linear_accel": [2.0, 1.0, 1.5],
        "max_angular_vel": 1.5,
        "max_angular_accel": 4.0,
    }
    agent = spawn(sim, {"type": "omni", **limits})
    waypoints = [Pose.from_euler(*rng.uniform(-3, 3, 3), yaw=rng.uniform(-3, 3)) for _ in range(4)]
    agent.set_path(waypoints)
    trace = run(sim, agent)
    vel = np.array([v for _, _, v, _ in trace])
    assert (np.abs(vel) <= np.array(limits["max_linear_vel"]) + TOL).all()
    assert (np.abs(accelerations(list(vel))) <= np.array(limits["max_linear_accel"]) + 1e-6).all()
    yaw_rate = np.array([w for _, _, _, w in trace])
    assert np.abs(yaw_rate).max() <= 1.5 + TOL
    assert np.allclose(agent.get_pose().position, waypoints[-1].position, atol=1e-12)
    assert agent.get_pose().orientation == pytest.approx(waypoints[-1].orientation, abs=1e-12)


def test_differential_rotates_in_place_then_drives_straight(sim):
    agent = spawn(sim, {"type": "differential", "max_angular_vel": 1.0, "max_angular_accel": 2.0})
    agent.set_path([Pose.from_xyz(0.0, 4.0, 0.1)], final_orientation_align=False)
    trace = run(sim, agent)
    turning = [t for t in trace if abs(t[3]) > 0]
    driving = [t for t in trace if np.linalg.norm(t[2]) > 0]
    assert turning and driving
    last_turn = max(i for i, t in enumerate(trace) if abs(t[3]) > 0)
    first_drive = min(i for i, t in enumerate(trace) if np.linalg.norm(t[2]) > 0)
    assert last_turn < first_drive  # rotate, then drive: never both
    for pos, _, _, _ in trace[: last_turn + 1]:
        assert pos.tolist() == [0.0, 0.0, 0.1]
    for _, yaw, vel, _ in driving:
        assert yaw == pytest.approx(math.pi / 2, abs=1e-12)
        assert vel[0] == pytest.approx(0.0, abs=1e-12) and vel[1] > 0
    rates = np.array([w for _, _, _, w in trace])
    assert np.abs(rates).max() <= 1.0 + TOL
    assert np.abs(accelerations(list(rates[:, None]))).max() <= 2.0 + 1e-6
    assert agent.get_pose().position.tolist() == [0.0, 4.0, 0.1]


def test_differential_final_orientation_align(sim):
    agent = spawn(sim, "differential")
    agent.set_path([Pose.from_euler(2.0, 2.0, 0.1, yaw=-1.0)])
    run(sim, agent)
    assert agent.get_pose().yaw == pytest.approx(-1.0, abs=1e-12)
    assert agent.get_pose().position.tolist() == [2.0, 2.0, 0.1]


def test_backward_keeps_its_heading(sim):
    agent = spawn(sim, "differential")
    agent.set_path(
        [Pose.from_xyz(-3.0, 0.0, 0.1)], final_orientation_align=False, direction="backward"
    )
    trace = run(sim, agent)
    assert all(abs(t[3]) == 0 for t in trace)  # already facing away from the goal: no turn
    assert all(yaw == pytest.approx(0.0, abs=1e-12) for _, yaw, _, _ in trace)
    assert agent.get_pose().position.tolist() == [-3.0, 0.0, 0.1]


def test_auto_direction_drives_backward_to_a_goal_behind(sim):
    agent = spawn(sim, "differential", yaw=0.2)
    agent.set_path([Pose.from_xyz(-3.0, 0.0, 0.1)], final_orientation_align=False, direction="auto")
    run(sim, agent)
    assert agent.get_pose().yaw == pytest.approx(0.0, abs=1e-12)  # turned by 0.2 rad, not pi
    forward = spawn(sim, "differential", xyz=(0.0, 5.0, 0.1))
    forward.set_path(
        [Pose.from_xyz(3.0, 5.0, 0.1)], final_orientation_align=False, direction="auto"
    )
    run(sim, forward)
    assert forward.get_pose().yaw == pytest.approx(0.0, abs=1e-12)


def test_path_progress_queries(sim):
    agent = spawn(sim, "omni")
    path = Path.from_positions([[1, 0, 0.1], [1, 1, 0.1], [0, 1, 0.1]])
    agent.set_path(path, final_orientation_align=False)
    assert agent.goal_pose.position.tolist() == [0, 1, 0.1]
    assert agent.current_waypoint_index == 0 and len(agent.path) == 3
    seen = {agent.current_waypoint_index}
    arrivals = []
    while agent.is_moving:
        before = agent.current_waypoint_index
        sim.step_once()
        seen.add(agent.current_waypoint_index)
        if agent.current_waypoint_index != before or not agent.is_moving:
            arrivals.append(agent.get_pose().position.tolist())
    assert seen == {0, 1, 2}
    assert arrivals == [[1, 0, 0.1], [1, 1, 0.1], [0, 1, 0.1]]
    assert agent.goal_pose is None and agent.path == []


def test_auto_approach_false_starts_from_the_first_waypoint(sim):
    agent = spawn(sim, "omni")
    agent.set_path(Path.from_positions([[5, 5, 0.1], [0, 2, 0.1]]), auto_approach=False)
    positions = [p for p, _, _, _ in run(sim, agent)]
    assert all(p[0] == pytest.approx(0.0, abs=1e-12) for p in positions)  # never went to (5, 5)
    assert positions[-1].tolist() == [0, 2, 0.1]


def test_stop_halts_in_the_same_step(sim):
    agent = spawn(sim, "omni")
    agent.set_goal_pose(Pose.from_xyz(10, 0, 0.1))
    for _ in range(10):
        sim.step_once()
    agent.stop()
    where = agent.get_pose().position.copy()
    assert not agent.is_moving and agent.motion_result is False
    assert agent.velocity.tolist() == [0, 0, 0] and agent.goal_pose is None
    sim.step_once()
    assert agent.get_pose().position.tolist() == where.tolist()


def test_new_goal_replaces_the_old_one(sim):
    agent = spawn(sim, "omni")
    agent.set_goal_pose(Pose.from_xyz(10, 0, 0.1))
    sim.step_once()
    agent.set_goal_pose(Pose.from_xyz(0, -2, 0.1))
    run(sim, agent)
    assert agent.get_pose().position.tolist() == [0, -2, 0.1]


def test_cmd_vel_accelerates_to_the_command_within_limits(sim):
    agent = spawn(sim, {"type": "differential", "max_linear_vel": 1.0, "max_linear_accel": 2.0})
    agent.set_cmd_vel(vx=0.8, wz=0.5)
    speeds = []
    for _ in range(20):
        sim.step_once()
        speeds.append(float(np.linalg.norm(agent.velocity)))
    # The command ramps by a * dt = 0.2 m/s per step; each step covers its mean speed.
    assert speeds[:5] == pytest.approx([0.1, 0.3, 0.5, 0.7, 0.8])
    assert speeds[-1] == pytest.approx(0.8) and agent.angular_velocity == pytest.approx(0.5)
    assert agent.is_moving
    with pytest.raises(ValueError, match="sideways"):
        agent.set_cmd_vel(vy=0.1)
    agent.set_cmd_vel(vx=5.0)  # clipped to the limit
    for _ in range(10):
        sim.step_once()
    assert float(np.linalg.norm(agent.velocity)) == pytest.approx(1.0)
    agent.stop()
    assert not agent.is_moving


def test_omni_moves_in_3d_and_sideways(sim):
    agent = spawn(sim, "omni")
    agent.set_cmd_vel(vy=0.5)
    for _ in range(30):
        sim.step_once()
    assert agent.get_pose().x == pytest.approx(0.0) and agent.get_pose().y > 0
    agent.set_goal_pose(Pose.from_xyz(1, 1, 2.0))
    run(sim, agent)
    assert agent.get_pose().position.tolist() == [1, 1, 2.0]


def test_fixed_base_ignores_motion_with_a_warning(sim, caplog):
    agent = spawn(sim, "omni", use_fixed_base=True)
    with caplog.at_level(logging.WARNING):
        agent.set_goal_pose(Pose.from_xyz(3, 0, 0.1))
    assert "fixed base" in caplog.text and not agent.is_moving
    sim.step_once()
    assert agent.get_pose().x == 0.0


def test_bad_paths_are_rejected(sim):
    agent = spawn(sim, "omni")
    with pytest.raises(ValueError, match=r"set_path\.path\[1\]: expected a Pose, got \[2, 0, 0\]"):
        agent.set_path([Pose.from_xyz(1, 0, 0), [2, 0, 0]])
    with pytest.raises(ValueError, match="Pose"):
        agent.set_goal_pose([1, 2, 3])
    with pytest.raises(ValueError, match="direction"):
        agent.set_path([Pose.from_xyz(1, 0, 0)], direction="sideways")


@pytest.mark.parametrize("path", [Path([]), []])
def test_an_empty_path_is_refused(sim, path):
    agent = spawn(sim, "omni")
    with pytest.raises(ValueError, match=r"set_path\.path: expected at least one waypoint"):
        agent.set_path(path)
    assert agent.motion_result is None


@pytest.mark.parametrize(
    "call",
    [
        lambda a: a.set_goal_pose((3, 0, 0)),
        lambda a: a.set_path((3, 0, 0)),
        lambda a: MoveAction(path=(3, 0, 0)),
    ],
)
def test_a_tuple_goal_is_reported_as_what_it_is(sim, call):
    agent = spawn(sim, "omni")
    with pytest.raises(ValueError, match=r"got \(3, 0, 0\) .*Pose\.from_xyz\(x, y, z\)"):
        call(agent)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("name", ["vx", "vy", "wz", "vz"])
def test_cmd_vel_refuses_nan_and_infinities(sim, name, bad):
    agent = spawn(sim, "omni")
    with pytest.raises(ValueError, match=rf"set_cmd_vel\.{name}: expected a finite number.*{bad}"):
        agent.set_cmd_vel(**{name: bad})
    sim.step_once()
    assert np.isfinite(agent.get_pose().position).all() and not agent.is_moving


def test_many_agents_move_independently_in_one_pass(sim):
    agents = [spawn(sim, "omni" if i % 2 else "differential", xyz=(i, 0, 0.1)) for i in range(20)]
    for i, agent in enumerate(agents):
        agent.set_goal_pose(Pose.from_xyz(i, 3 + i % 4, 0.1))
    for _ in range(200):
        sim.step_once()
    for i, agent in enumerate(agents):
        assert agent.get_pose().position.tolist() == [i, 3 + i % 4, 0.1]
        assert not agent.is_moving


# ----- timing of the exact trapezoid (issue 15, item 5) -------------------------------------


@pytest.mark.parametrize(
    ("distance", "timestep", "steps"),
    [
        (2.0, 0.1, 14),  # 0.4 s up, 0.6 s at 2 m/s, 0.4 s down: 1.4 s
        (2.0, 0.01, 140),
        (10.0, 0.1, 54),  # 5.4 s
        (0.3, 0.1, 5),  # a triangle: 2 * sqrt(0.3 / 5) = 0.49 s, done in the step covering it
    ],
)
def test_a_move_takes_the_fastest_time_the_limits_allow(distance, timestep, steps):
    with MultiRobotSimulationCore(headless_params(timestep=timestep)) as sim:
        agent = spawn(sim, "omni")
        action = MoveAction(path=Pose.from_xyz(distance, 0.0, 0.1))
        agent.add_action(action)
        trace = run(sim, agent, max_steps=10 * steps)
        assert len(trace) == steps
        assert action.is_complete() and sim.step_count == steps
        assert action.start_time == 0.0
        assert action.end_time == pytest.approx(steps * timestep, abs=1e-12)
        assert agent.get_pose().position.tolist() == [distance, 0.0, 0.1]


def test_every_step_stays_within_what_the_limits_allow_from_rest(sim):
    agent = spawn(sim, {"type": "omni", "max_linear_vel": 2.0, "max_linear_accel": 5.0})
    agent.set_goal_pose(Pose.from_xyz(2.0, 0.0, 0.1))
    xs = [0.0] + [float(p[0]) for p, _, _, _ in run(sim, agent)]
    # Sampled exactly: x(t) = a t^2 / 2 while accelerating, then 2 m/s, then the mirror image.
    assert xs[1:5] == pytest.approx([0.025, 0.1, 0.225, 0.4])
    assert xs[-5:] == pytest.approx([1.6, 1.775, 1.9, 1.975, 2.0])
    steps = np.diff(xs)
    assert steps.max() <= 2.0 * DT + TOL
    # Between two steps the mean speed changes by at most a * dt.
    assert np.abs(np.diff(np.concatenate([[0.0], steps / DT, [0.0]]))).max() <= 5.0 * DT + 1e-9


def test_omni_final_orientation_align_drives_then_turns(sim):
    agent = spawn(sim, "omni")
    agent.set_goal_pose(Pose.from_euler(2.0, 0.0, 0.1, yaw=math.pi / 2))
    trace = run(sim, agent)
    yaws = [yaw for _, yaw, _, _ in trace]
    xs = [float(p[0]) for p, _, _, _ in trace]
    arrival = xs.index(2.0)
    assert arrival == 13  # the 14th step arrives, still at yaw 0
    assert all(y == pytest.approx(0.0) for y in yaws[: arrival + 1])
    # Then it turns in place: 90 degrees at 3 rad/s, 10 rad/s^2 take 0.3 + (pi / 2) / 3 s, 9 steps.
    assert all(x == 2.0 for x in xs[arrival:])
    assert yaws[-1] == pytest.approx(math.pi / 2)
    assert len(trace) == arrival + 1 + 9


def test_omni_path_keeps_its_orientation_through_intermediate_waypoints(sim):
    agent = spawn(sim, "omni")
    path = [Pose.from_euler(1.0, 0.0, 0.1, yaw=1.0), Pose.from_euler(1.0, 1.0, 0.1, yaw=-2.0)]
    agent.set_path(path)
    trace = run(sim, agent)
    at_corner = next(i for i, (p, _, _, _) in enumerate(trace) if p.tolist() == [1.0, 0.0, 0.1])
    assert trace[at_corner][1] == pytest.approx(0.0)
    assert agent.get_pose().yaw == pytest.approx(-2.0)


def test_cmd_vel_first_step_moves_half_a_dt_squared(sim):
    agent = spawn(sim, {"type": "omni", "max_linear_vel": 2.0, "max_linear_accel": 5.0})
    agent.set_cmd_vel(vx=2.0)
    xs = []
    for _ in range(6):
        sim.step_once()
        xs.append(agent.get_pose().x)
    assert xs == pytest.approx([0.025, 0.1, 0.225, 0.4, 0.6, 0.8])


def _arrival_changes(handler_acts: bool):
    """Robot a completes a move; at that moment velocity robot b is removed, a new robot d
    takes b's freed engine slot, and idle robot c gets a velocity command: from the action's
    completion handler (inside the step's motion phase) or, for reference, from outside,
    before the same step. Returns (d, c, the step of the change, the simulation)."""
    sim = MultiRobotSimulationCore(headless_params())
    a = spawn(sim, name="a")
    b = spawn(sim, xyz=(0.0, 5.0, 0.1), name="b")
    c = spawn(sim, xyz=(0.0, -5.0, 0.1), name="c")
    b.set_cmd_vel(1.0, 0.0, 0.0, 0.0)
    new: list[Agent] = []

    def change() -> None:
        sim.remove_object(b)
        new.append(spawn(sim, xyz=(3.0, 3.0, 0.1), name="d"))
        c.set_cmd_vel(1.0, 0.0, 0.0, 0.0)

    if handler_acts:
        sim.events.on(
            "action_completed", lambda agent, **_: change() if agent is a and not new else None
        )
    a.add_action(MoveAction(path=Path([Pose.from_xyz(0.5, 0.0, 0.1)])))
    changed_at = None
    for step in range(30):
        if not handler_acts and step == 6:  # the step in which a's move completes
            change()
        sim.step_once()
        if new and changed_at is None:
            changed_at = step
    return new[0], c, changed_at, sim


def test_modes_changed_by_an_arrivals_callbacks_apply_in_the_same_step():
    d, c, at, sim = _arrival_changes(handler_acts=True)
    _, c_ref, at_ref, sim_ref = _arrival_changes(handler_acts=False)
    assert at == at_ref == 6
    # d reuses b's slot but not b's velocity command; c starts in the step it was told to.
    assert d.get_pose().position.tolist() == [3.0, 3.0, 0.1] and not d.is_moving
    assert c.get_pose().position.tolist() == c_ref.get_pose().position.tolist()
    assert c.get_pose().x > 2.0
    sim.close()
    sim_ref.close()
