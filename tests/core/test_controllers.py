"""Controller argument forms, chain management, and the built-in high-level controllers."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from fleet_async import (
    Agent,
    Controller,
    ControllerParams,
    DifferentialController,
    KinematicController,
    MotionMode,
    MovementDirection,
    MultiRobotSimulationCore,
    OmniController,
    PatrolController,
    Pose,
    RandomWalkController,
    ShapeParams,
    create_controller,
    register_controller,
)
from fleet_async.core.motion.controllers import CONTROLLER_REGISTRY
from tests.conftest import headless_params

DT = 0.1
TOL = 1e-9
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
DEFAULT_LIMITS = {
    "max_linear_vel": 2.0,
    "max_linear_accel": 5.0,
    "max_angular_vel": 3.0,
    "max_angular_accel": 10.0,
}


def spawn(sim, controller=None, xyz=(0.0, 0.0, 0.1), **kw):
    return Agent.from_mesh(BOX, BOX, Pose.from_xyz(*xyz), sim_core=sim, controller=controller, **kw)


def limits_of(params: ControllerParams) -> dict[str, object]:
    return {name: getattr(params, name) for name in DEFAULT_LIMITS}


def run_until_stopped(sim, agent, max_steps=500) -> list[np.ndarray]:
    """Step until the agent stops; return its position after every step."""
    positions = []
    for _ in range(max_steps):
        sim.step_once()
        positions.append(agent.get_pose().position.copy())
        if not agent.is_moving:
            return positions
    raise AssertionError(f"agent still moving after {max_steps} steps")


def record(sim, agent, steps):
    """Step ``steps`` times; return [(step_count, is_moving, position)] after each step."""
    trace = []
    for _ in range(steps):
        sim.step_once()
        trace.append((sim.step_count, agent.is_moving, agent.get_pose().position.copy()))
    return trace


def arrivals_and_departures(trace):
    """Step counts at which motion ended, and the step counts of the steps that started one.

    A step that starts a motion is the one *before* the first step count at which the agent is
    reported moving: it begins at sim time ``(count - 1) * DT``.
    """
    arrivals, departures, moving = [], [], False
    for count, is_moving, position in trace:
        if moving and not is_moving:
            arrivals.append((count, position))
        if is_moving and not moving:
            departures.append(count - 1)
        moving = is_moving
    return arrivals, departures


class StepRecorder(Controller):
    """A high-level controller that records every compute call."""

    def __init__(self, params: ControllerParams | None = None) -> None:
        super().__init__(params)
        self.calls: list[tuple[object, int, float]] = []
        self.hooks: list[str] = []

    def on_install(self, agent):
        self.hooks.append("install")

    def on_remove(self, agent):
        self.hooks.append("remove")

    def compute(self, agent, dt):
        self.calls.append((agent, agent.sim_core.step_count, dt))


@pytest.fixture
def registry():
    """CONTROLLER_REGISTRY, restored after the test."""
    saved = dict(CONTROLLER_REGISTRY)
    yield CONTROLLER_REGISTRY
    CONTROLLER_REGISTRY.clear()
    CONTROLLER_REGISTRY.update(saved)


# ----- argument forms --------------------------------------------------------------------


def test_none_gives_a_differential_base_with_default_params(sim):
    agent = spawn(sim)
    base = agent.controller
    assert type(base) is DifferentialController and agent.controllers == [base]
    assert limits_of(base.params) == DEFAULT_LIMITS
    assert base.params.default_direction is MovementDirection.FORWARD
    assert base.wheel_separation == 0.3
    assert agent.motion_mode is MotionMode.DIFFERENTIAL
    assert agent.max_linear_vel.tolist() == [2.0, 2.0, 2.0]
    assert agent.max_linear_accel.tolist() == [5.0, 5.0, 5.0]
    assert agent.max_angular_vel.tolist() == [3.0, 3.0, 3.0]
    assert agent.max_angular_accel.tolist() == [10.0, 10.0, 10.0]
    assert agent.motion_slot >= 0


def test_none_with_omni_motion_mode_gives_an_omni_base(sim):
    agent = spawn(sim, motion_mode="omnidirectional")
    assert type(agent.controller) is OmniController
    assert agent.motion_mode is MotionMode.OMNIDIRECTIONAL
    assert limits_of(agent.controller_params) == DEFAULT_LIMITS


@pytest.mark.parametrize(
    ("name", "cls", "mode"),
    [
        ("omni", OmniController, MotionMode.OMNIDIRECTIONAL),
        ("omnidirectional", OmniController, MotionMode.OMNIDIRECTIONAL),
        ("differential", DifferentialController, MotionMode.DIFFERENTIAL),
    ],
)
def test_registry_name_selects_the_base(sim, name, cls, mode):
    agent = spawn(sim, name)
    assert type(agent.controller) is cls and len(agent.controllers) == 1
    assert agent.motion_mode is mode
    assert limits_of(agent.controller_params) == DEFAULT_LIMITS


def test_mapping_puts_params_in_params_and_extras_in_the_constructor(sim):
    agent = spawn(sim, {"type": "differential", "max_linear_vel": 1.5, "wheel_separation": 0.4})
    base = agent.controller
    assert type(base) is DifferentialController
    assert base.wheel_separation == 0.4
    assert limits_of(base.params) == {**DEFAULT_LIMITS, "max_linear_vel": 1.5}
    assert not hasattr(base.params, "wheel_separation")
    assert agent.max_linear_vel.tolist() == [1.5, 1.5, 1.5]


def test_mapping_params_reach_the_motion(sim):
    agent = spawn(sim, {"type": "omni", "max_linear_vel": 1.5})
    agent.set_goal_pose(Pose.from_xyz(6.0, 0.0, 0.1))
    positions = run_until_stopped(sim, agent)
    steps = np.diff(np.vstack([[0.0, 0.0, 0.1], *positions]), axis=0)
    speeds = np.linalg.norm(steps, axis=1) / DT
    assert speeds.max() == pytest.approx(1.5, abs=TOL)
    assert positions[-1].tolist() == [6.0, 0.0, 0.1]


@pytest.mark.parametrize(
    ("motion_mode", "cls"),
    [("differential", DifferentialController), ("omnidirectional", OmniController)],
)
def test_mapping_without_type_keeps_the_default_base(sim, motion_mode, cls):
    agent = spawn(sim, {"max_linear_vel": 1.2}, motion_mode=motion_mode)
    assert type(agent.controller) is cls and len(agent.controllers) == 1
    assert limits_of(agent.controller_params) == {**DEFAULT_LIMITS, "max_linear_vel": 1.2}


def test_class_path_selects_the_controller(sim):
    agent = spawn(
        sim, {"class": "fleet_async.core.motion.controllers.OmniController", "max_angular_vel": 1.0}
    )
    assert type(agent.controller) is OmniController
    assert agent.motion_mode is MotionMode.OMNIDIRECTIONAL
    assert agent.controller_params.max_angular_vel == 1.0


def test_list_gives_base_then_high_level(sim):
    agent = spawn(
        sim,
        [
            {"type": "omni"},
            {"type": "patrol", "waypoints": [[1, 0, 0.1], [1, 1, 0.1]], "wait": 0.5},
        ],
    )
    base, patrol = agent.controllers
    assert type(base) is OmniController and type(patrol) is PatrolController
    assert base.is_base and not patrol.is_base
    assert [w.position.tolist() for w in patrol.waypoints] == [[1.0, 0.0, 0.1], [1.0, 1.0, 0.1]]
    assert patrol.wait == 0.5 and patrol.loop is True
    assert agent.has_stepped_controllers()


def test_list_with_the_high_level_entry_first_still_puts_the_base_first(sim):
    agent = spawn(sim, [{"type": "random_walk", "radius": 2.0}, "omni"])
    assert [type(c) for c in agent.controllers] == [OmniController, RandomWalkController]


def test_list_of_controller_instances(sim):
    base, recorder = OmniController(max_linear_vel=0.5), StepRecorder()
    agent = spawn(sim, [base, recorder])
    assert agent.controllers == [base, recorder]
    assert recorder.hooks == ["install"]


@pytest.mark.parametrize(
    ("motion_mode", "cls"),
    [("differential", DifferentialController), ("omnidirectional", OmniController)],
)
def test_lone_high_level_entry_gets_a_base_from_motion_mode(sim, motion_mode, cls):
    spec = {"type": "patrol", "waypoints": [[1, 0, 0.1]], "wait": 0.5}
    agent = spawn(sim, spec, motion_mode=motion_mode)
    base, patrol = agent.controllers
    assert type(base) is cls and type(patrol) is PatrolController
    assert limits_of(base.params) == DEFAULT_LIMITS


def test_controller_params_instance_becomes_the_base_params(sim):
    params = ControllerParams(max_linear_vel=0.5, max_angular_accel=[1, 2, 3])
    agent = spawn(sim, params)
    assert type(agent.controller) is DifferentialController and len(agent.controllers) == 1
    assert limits_of(agent.controller_params) == {
        **DEFAULT_LIMITS,
        "max_linear_vel": 0.5,
        "max_angular_accel": (1.0, 2.0, 3.0),
    }


def test_controller_params_direction_is_used_by_set_path(sim):
    agent = spawn(sim, ControllerParams(default_direction="backward"))
    agent.set_path([Pose.from_xyz(1.0, 0.0, 0.1)], final_orientation_align=False)
    run_until_stopped(sim, agent)
    # Driving backward to +x means facing -x the whole way.
    assert abs(agent.get_pose().yaw) == pytest.approx(math.pi, abs=1e-9)
    assert agent.get_pose().position.tolist() == [1.0, 0.0, 0.1]


def test_base_controller_instance_is_installed_as_is(sim):
    base = OmniController(max_linear_vel=0.7)
    agent = spawn(sim, base)
    assert agent.controller is base and agent.controllers == [base]
    assert agent.max_linear_vel.tolist() == [0.7, 0.7, 0.7]
    assert base.vectorized and agent.motion_slot >= 0


def test_high_level_controller_instance_gets_a_default_base(sim):
    patrol = PatrolController([[1, 0, 0.1]])
    agent = spawn(sim, patrol)
    assert type(agent.controller) is DifferentialController
    assert agent.controllers[1] is patrol and len(agent.controllers) == 2


def test_per_axis_limits_are_reported_as_arrays(sim):
    agent = spawn(sim, {"type": "omni", "max_linear_vel": [1, 2, 3]})
    assert agent.controller_params.max_linear_vel == (1.0, 2.0, 3.0)
    assert isinstance(agent.max_linear_vel, np.ndarray)
    assert agent.max_linear_vel.tolist() == [1.0, 2.0, 3.0]
    assert agent.max_angular_vel.tolist() == [3.0, 3.0, 3.0]
    # A copy: changing it does not change the limits.
    agent.max_linear_vel[0] = 99.0
    assert agent.max_linear_vel.tolist() == [1.0, 2.0, 3.0]


def test_per_axis_limit_caps_each_axis_of_the_motion(sim):
    agent = spawn(sim, {"type": "omni", "max_linear_vel": [1, 2, 3]})
    agent.set_goal_pose(Pose.from_xyz(5.0, 0.0, 0.1))
    positions = run_until_stopped(sim, agent)
    vx = np.diff([0.0, *(pos[0] for pos in positions)]) / DT
    assert vx.max() == pytest.approx(1.0, abs=TOL)
    assert positions[-1].tolist() == [5.0, 0.0, 0.1]


# ----- bad inputs ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        ({"type": "hover"}, r"controller\.type: unknown controller 'hover'; known: \["),
        ({"type": "omni", "max_speed": 1.0}, "max_speed"),
        ({"type": "differential", "wheel_base": 0.4}, "wheel_base"),
        ({"type": "patrol", "waypoints": [[1, 0, 0]], "speed": 1.0}, "speed"),
        (
            {"type": "omni", "class": "fleet_async.core.motion.controllers.OmniController"},
            "either 'type' or 'class', not both",
        ),
        ({"type": "omni", "max_linear_vel": -1.0}, r"max_linear_vel.*-1\.0"),
        ({"type": "omni", "max_angular_vel": 0}, "max_angular_vel"),
        ({"type": "omni", "max_linear_accel": float("nan")}, "max_linear_accel"),
        ({"type": "omni", "max_linear_vel": True}, "max_linear_vel"),
        ({"type": "omni", "max_linear_accel": [1.0, 2.0]}, r"max_linear_accel.*\[1\.0, 2\.0\]"),
        ({"type": "omni", "max_angular_accel": [1.0, -2.0, 3.0]}, "max_angular_accel"),
        ({"max_linear_vel": [1.0, 2.0, 3.0, 4.0]}, "max_linear_vel"),
        (
            {"class": "fleet_async.core.geometry.pose.Pose"},
            r"controller\.class: 'fleet_async\.core\.geometry\.pose\.Pose' is not a Controller",
        ),
        ({"type": "differential", "wheel_separation": 0.0}, "wheel_separation"),
        ({"type": "patrol", "waypoints": []}, "PatrolController.waypoints"),
        ({"type": "patrol", "waypoints": [[1, 0, 0]], "wait": -1.0}, "PatrolController.wait"),
        ({"type": "random_walk", "radius": 0.0}, "RandomWalkController.radius"),
        ({"type": "random_walk", "wait_range": [2.0, 1.0]}, "RandomWalkController.wait_range"),
        ({"type": "omni", "default_direction": "sideways"}, "default_direction"),
    ],
)
def test_bad_controller_spec_is_a_value_error_naming_the_problem(sim, spec, match):
    with pytest.raises(ValueError, match=match):
        spawn(sim, spec)
    assert sim.agents == []


def test_unknown_type_lists_every_known_name(sim):
    with pytest.raises(ValueError, match="hover") as info:
        spawn(sim, "hover")
    for name in ("omni", "omnidirectional", "differential", "patrol", "random_walk"):
        assert repr(name) in str(info.value)


def test_bad_entry_in_a_list_is_named_by_index(sim):
    with pytest.raises(ValueError, match=r"controller\[1\]\.type: unknown controller 'hover'"):
        spawn(sim, ["omni", {"type": "hover"}])


def test_value_that_is_no_controller_spec_is_a_value_error(sim):
    with pytest.raises(ValueError, match="expected a name, mapping or Controller, got 42"):
        spawn(sim, 42)


def test_controller_params_validate_directly():
    with pytest.raises(ValueError, match=r"ControllerParams\.max_linear_vel"):
        ControllerParams(max_linear_vel=-2.0)
    with pytest.raises(ValueError, match=r"ControllerParams\.max_angular_vel"):
        ControllerParams(max_angular_vel=[1.0, 2.0])
    with pytest.raises(ValueError, match="unknown parameter"):
        OmniController(max_speed=1.0)


def test_rejected_controller_spec_leaves_no_pybullet_body(sim):
    bodies = p.getNumBodies(physicsClientId=sim.client)
    with pytest.raises(ValueError, match="hover"):
        spawn(sim, {"type": "hover"})
    assert sim.agents == []
    assert p.getNumBodies(physicsClientId=sim.client) == bodies


def test_mapping_without_type_is_a_value_error_in_create_controller():
    # The Agent argument takes a type-less mapping as "default base"; create_controller has
    # no motion mode to pick one from, so it must say what is missing.
    with pytest.raises(ValueError, match="type"):
        create_controller({"max_linear_vel": 1.2})


def test_two_base_controllers_in_a_list_is_a_value_error(sim):
    # A chain has one base; silently dropping one of two configured bases loses config.
    with pytest.raises(ValueError, match=r"controller\[1\]"):
        spawn(sim, [{"type": "omni", "max_linear_vel": 1.0}, {"type": "differential"}])


def test_differential_type_under_omni_motion_mode_warns(sim, caplog):
    with caplog.at_level("WARNING", logger="fleet_async.core.motion.controllers"):
        agent = spawn(sim, "differential", motion_mode="omnidirectional")
    assert type(agent.controller) is DifferentialController
    assert "overrides motion_mode=omnidirectional" in caplog.text


# ----- set_controller / add_controller / remove_controller -------------------------------


def test_set_controller_replaces_base_and_keeps_high_level(sim):
    agent = spawn(sim, ["omni", {"type": "patrol", "waypoints": [[1, 0, 0.1]], "loop": False}])
    old_base, patrol = agent.controllers
    agent.set_controller({"type": "differential", "max_linear_vel": 1.0, "wheel_separation": 0.5})
    base = agent.controller
    assert type(base) is DifferentialController and base is not old_base
    assert agent.controllers == [base, patrol]
    assert agent.motion_mode is MotionMode.DIFFERENTIAL
    assert agent.max_linear_vel.tolist() == [1.0, 1.0, 1.0] and base.wheel_separation == 0.5
    # The patrol now drives the new base: rotate to face +x (already does), drive 1 m.
    run_until_stopped(sim, agent)
    assert agent.get_pose().position.tolist() == [1.0, 0.0, 0.1] and patrol.index == 0


def test_set_controller_accepts_names_and_instances(sim):
    agent = spawn(sim)
    agent.set_controller("omni")
    assert type(agent.controller) is OmniController
    base = OmniController(max_linear_vel=0.25)
    agent.set_controller(base)
    assert agent.controller is base and agent.max_linear_vel.tolist() == [0.25, 0.25, 0.25]


def test_set_controller_keeps_high_level_controllers_installed(sim):
    recorder = StepRecorder()
    agent = spawn(sim, ["omni", recorder])
    agent.set_controller("differential")
    # Kept controllers never left the chain, so they are neither removed nor re-installed.
    assert recorder.hooks == ["install"]


def test_set_controller_tells_the_replaced_base(sim):
    removed = []

    class TrackedOmni(OmniController):
        def on_remove(self, agent):
            removed.append(agent)

    agent = spawn(sim, TrackedOmni())
    agent.set_controller("differential")
    assert removed == [agent]


def test_set_controller_stops_the_motion_in_progress(sim):
    agent = spawn(sim, "omni")
    agent.set_goal_pose(Pose.from_xyz(5.0, 0.0, 0.1))
    for _ in range(3):
        sim.step_once()
    where = agent.get_pose().position.copy()
    agent.set_controller("differential")
    assert not agent.is_moving and agent.motion_result is False and agent.goal_pose is None
    sim.step_once()
    assert agent.get_pose().position.tolist() == where.tolist()


def test_set_controller_rejects_a_high_level_controller(sim):
    agent = spawn(sim, "omni")
    base = agent.controller
    with pytest.raises(ValueError, match="PatrolController is not a base controller"):
        agent.set_controller(PatrolController([[1, 0, 0.1]]))
    with pytest.raises(ValueError, match="not a base controller"):
        agent.set_controller({"type": "random_walk"})
    assert agent.controllers == [base]


def test_set_controller_none_disables_movement(sim, caplog):
    agent = spawn(sim, "omni")
    agent.set_controller(None)
    assert agent.controller is None and agent.controllers == [] and agent.motion_slot == -1
    assert limits_of(agent.controller_params) == DEFAULT_LIMITS
    with caplog.at_level("WARNING", logger="fleet_async.core.agents.agent_motion"):
        agent.set_goal_pose(Pose.from_xyz(1.0, 0.0, 0.1))
    assert "no base controller" in caplog.text
    for _ in range(10):
        sim.step_once()
    assert not agent.is_moving and agent.goal_pose is None and agent.path == []
    assert agent.get_pose().position.tolist() == [0.0, 0.0, 0.1]
    # Movement comes back with a base.
    agent.set_controller("omni")
    agent.set_goal_pose(Pose.from_xyz(1.0, 0.0, 0.1))
    run_until_stopped(sim, agent)
    assert agent.get_pose().position.tolist() == [1.0, 0.0, 0.1]


def test_add_controller_appends_and_runs_a_high_level_controller(sim):
    agent = spawn(sim, "omni")
    assert not agent.has_stepped_controllers()
    recorder = StepRecorder()
    agent.add_controller(recorder)
    assert agent.controllers[1] is recorder and recorder.hooks == ["install"]
    sim.step_once()
    assert [(a, n, dt) for a, n, dt in recorder.calls] == [(agent, 0, DT)]


def test_add_controller_rejects_base_controllers_and_non_controllers(sim):
    agent = spawn(sim, "omni")
    with pytest.raises(ValueError, match="DifferentialController is a base controller"):
        agent.add_controller(DifferentialController())
    with pytest.raises(TypeError, match="expected a Controller"):
        agent.add_controller("patrol")
    assert len(agent.controllers) == 1
    agent.set_controller(None)
    with pytest.raises(ValueError, match="no base controller"):
        agent.add_controller(StepRecorder())


def test_remove_controller_by_instance(sim):
    recorder = StepRecorder()
    agent = spawn(sim, ["omni", recorder])
    sim.step_once()
    assert agent.remove_controller(recorder) is True
    assert len(agent.controllers) == 1 and recorder.hooks == ["install", "remove"]
    sim.step_once()
    assert len(recorder.calls) == 1  # not called after removal
    assert agent.remove_controller(recorder) is False


def test_remove_controller_by_class_removes_the_first_match(sim):
    agent = spawn(
        sim,
        [
            "omni",
            {"type": "patrol", "waypoints": [[1, 0, 0.1]]},
            {"type": "random_walk"},
            {"type": "patrol", "waypoints": [[2, 0, 0.1]]},
        ],
    )
    base, first, walk, second = agent.controllers
    assert agent.remove_controller(PatrolController) is True
    assert agent.controllers == [base, walk, second] and first not in agent.controllers
    assert agent.remove_controller(RandomWalkController) is True
    assert agent.controllers == [base, second]


def test_remove_controller_never_removes_the_base(sim):
    agent = spawn(sim, "omni")
    base = agent.controller
    assert agent.remove_controller(base) is False
    assert agent.remove_controller(OmniController) is False
    assert agent.remove_controller(KinematicController) is False
    assert agent.remove_controller(Controller) is False
    assert agent.controllers == [base] and agent.motion_slot >= 0


def test_get_controller_by_type(sim):
    agent = spawn(sim, ["omni", {"type": "patrol", "waypoints": [[1, 0, 0.1]]}])
    base, patrol = agent.controllers
    assert agent.get_controller_by_type(OmniController) is base
    assert agent.get_controller_by_type(KinematicController) is base
    assert agent.get_controller_by_type(Controller) is base
    assert agent.get_controller_by_type(PatrolController) is patrol
    assert agent.get_controller_by_type(RandomWalkController) is None
    assert agent.get_controller_by_type(DifferentialController) is None


# ----- motion_mode -----------------------------------------------------------------------


def test_motion_mode_follows_the_base_controller(sim):
    agent = spawn(sim, "omni", motion_mode="differential")
    assert agent.motion_mode is MotionMode.OMNIDIRECTIONAL
    agent.set_controller("differential")
    assert agent.motion_mode is MotionMode.DIFFERENTIAL


@pytest.mark.filterwarnings("ignore:Agent.set_motion_mode is deprecated:DeprecationWarning")
def test_set_motion_mode_swaps_the_base_and_keeps_params_and_high_level(sim):
    agent = spawn(
        sim,
        [
            {"type": "differential", "max_linear_vel": 1.5},
            {"type": "patrol", "waypoints": [[1, 0, 0.1]]},
        ],
    )
    patrol = agent.controllers[1]
    agent.set_motion_mode("omnidirectional")
    assert type(agent.controller) is OmniController
    assert agent.motion_mode is MotionMode.OMNIDIRECTIONAL
    assert agent.controllers[1] is patrol and len(agent.controllers) == 2
    assert limits_of(agent.controller_params) == {**DEFAULT_LIMITS, "max_linear_vel": 1.5}
    agent.set_motion_mode(MotionMode.DIFFERENTIAL)
    assert type(agent.controller) is DifferentialController


@pytest.mark.filterwarnings("ignore:Agent.set_motion_mode is deprecated:DeprecationWarning")
def test_set_motion_mode_raises_while_moving(sim):
    agent = spawn(sim, "omni")
    base = agent.controller
    agent.set_goal_pose(Pose.from_xyz(3.0, 0.0, 0.1))
    sim.step_once()
    with pytest.raises(ValueError, match="while moving"):
        agent.set_motion_mode("differential")
    assert agent.controller is base and agent.is_moving
    agent.set_cmd_vel(vx=0.5)
    sim.step_once()
    with pytest.raises(ValueError, match="while moving"):
        agent.set_motion_mode("differential")
    agent.stop()
    agent.set_motion_mode("differential")
    assert type(agent.controller) is DifferentialController


@pytest.mark.filterwarnings("ignore:Agent.set_motion_mode is deprecated:DeprecationWarning")
def test_set_motion_mode_rejects_an_unknown_mode(sim):
    agent = spawn(sim, "omni")
    with pytest.raises(ValueError, match="motion_mode"):
        agent.set_motion_mode("sideways")
    assert type(agent.controller) is OmniController


def test_set_motion_mode_is_deprecated(sim):
    agent = spawn(sim, "omni")
    with pytest.deprecated_call(match="set_controller"):
        agent.set_motion_mode("differential")


# ----- register_controller / create_controller -------------------------------------------


def test_register_controller_makes_a_type_name_usable(sim, registry):
    register_controller("recorder", StepRecorder)
    assert isinstance(create_controller("recorder"), StepRecorder)
    agent = spawn(sim, ["omni", {"type": "recorder"}])
    recorder = agent.controllers[1]
    assert type(recorder) is StepRecorder
    for _ in range(3):
        sim.step_once()
    assert [n for _, n, _ in recorder.calls] == [0, 1, 2]
    with pytest.raises(ValueError, match="'recorder'"):
        spawn(sim, {"type": "no_such"})


def test_register_controller_with_a_base_class(sim, registry):
    class SlowOmni(OmniController):
        def __init__(self, params=None, **overrides):
            super().__init__(params, **{"max_linear_vel": 0.5, **overrides})

    register_controller("slow_omni", SlowOmni)
    agent = spawn(sim, "slow_omni")
    assert type(agent.controller) is SlowOmni and agent.controller.vectorized
    agent.set_goal_pose(Pose.from_xyz(2.0, 0.0, 0.1))
    positions = run_until_stopped(sim, agent)
    speeds = np.diff([0.0, *(pos[0] for pos in positions)]) / DT
    assert speeds.max() == pytest.approx(0.5, abs=TOL)


def test_register_controller_rejects_a_non_controller(registry):
    with pytest.raises(TypeError, match="not a Controller subclass"):
        register_controller("pose", Pose)
    with pytest.raises(TypeError, match="not a Controller subclass"):
        register_controller("instance", StepRecorder())
    assert "pose" not in registry and "instance" not in registry


def test_create_controller_forms():
    omni = create_controller("omni", {"max_linear_vel": 0.8})
    assert type(omni) is OmniController and omni.params.max_linear_vel == 0.8
    diff = create_controller({"type": "differential", "wheel_separation": 0.6})
    assert type(diff) is DifferentialController and diff.wheel_separation == 0.6
    walk = create_controller({"class": "fleet_async.core.motion.controllers.RandomWalkController"})
    assert type(walk) is RandomWalkController and walk.radius == 5.0
    with pytest.raises(ValueError, match=r"robots\[3\]\.controller\.type: unknown controller"):
        create_controller({"type": "hover"}, where="robots[3].controller")


# ----- PatrolController ------------------------------------------------------------------

PATROL_POINTS = [[1.0, 0.0, 0.1], [1.0, 1.0, 0.1], [0.0, 1.0, 0.1]]


def test_patrol_without_loop_visits_each_waypoint_in_order_and_stops(sim):
    agent = spawn(
        sim, ["omni", {"type": "patrol", "waypoints": PATROL_POINTS, "wait": 0.5, "loop": False}]
    )
    patrol = agent.controllers[1]
    trace = record(sim, agent, 120)
    arrivals, departures = arrivals_and_departures(trace)
    assert len(arrivals) == len(PATROL_POINTS)
    for (_, pos), point in zip(arrivals, PATROL_POINTS, strict=True):
        assert np.abs(pos - point).max() <= TOL
    # Every leg is 1 m from rest to rest, so every leg takes the same number of steps.
    arrival_steps = [n for n, _ in arrivals]
    leg = arrival_steps[0]
    assert departures[0] == 0
    assert arrival_steps == [leg, 2 * leg + 5, 3 * leg + 10]
    # wait = 0.5 s = 5 whole steps between arriving and setting off again.
    assert [d - a for a, d in zip(arrival_steps, departures[1:], strict=False)] == [5, 5]
    assert len(departures) == 3 and patrol.finished
    assert not trace[-1][1] and trace[-1][2].tolist() == PATROL_POINTS[-1]


def test_patrol_with_loop_comes_back_to_the_first_waypoint(sim):
    points = [[1.0, 0.0, 0.1], [1.0, 1.0, 0.1]]
    agent = spawn(sim, ["omni", {"type": "patrol", "waypoints": points, "wait": 0.2}])
    patrol = agent.controllers[1]
    arrivals, departures = arrivals_and_departures(record(sim, agent, 120))
    assert len(arrivals) >= 4 and not patrol.finished
    for i, (_, pos) in enumerate(arrivals):
        assert np.abs(pos - points[i % 2]).max() <= TOL
    arrival_steps = [n for n, _ in arrivals]
    assert [d - a for a, d in zip(arrival_steps, departures[1:], strict=False)] == [2] * (
        len(departures) - 1
    )


def test_patrol_with_zero_wait_sets_off_in_the_step_after_arriving(sim):
    agent = spawn(sim, ["omni", {"type": "patrol", "waypoints": PATROL_POINTS[:2], "wait": 0}])
    arrivals, departures = arrivals_and_departures(record(sim, agent, 60))
    arrival_steps = [n for n, _ in arrivals]
    assert [d - a for a, d in zip(arrival_steps, departures[1:], strict=False)] == [0] * (
        len(departures) - 1
    )


# ----- RandomWalkController --------------------------------------------------------------


def walk_positions(sim, steps=300, **walk):
    agent = spawn(sim, ["omni", {"type": "random_walk", **walk}])
    return agent, np.array([pos for _, _, pos in record(sim, agent, steps)])


def test_random_walk_stays_within_radius_of_its_default_center(sim):
    agent, positions = walk_positions(sim, radius=1.5, wait_range=[0.0, 0.3])
    walk = agent.controllers[1]
    assert walk.center.tolist() == [0.0, 0.0, 0.1]
    dist = np.linalg.norm(positions - walk.center, axis=1)
    assert dist.max() <= 1.5 + TOL
    assert dist.max() > 0.75  # it does wander
    assert (positions[:, 2] == 0.1).all()


def test_random_walk_targets_stay_within_radius_of_an_explicit_center(sim):
    center = [0.5, 0.0, 0.1]
    agent = spawn(
        sim,
        ["omni", {"type": "random_walk", "radius": 1.0, "center": center, "wait_range": [0, 0]}],
    )
    goals = []
    for _ in range(300):
        sim.step_once()
        position = agent.get_pose().position
        assert np.linalg.norm(position - center) <= 1.0 + TOL
        if agent.goal_pose is not None:
            goals.append(agent.goal_pose.position.copy())
    distinct = {tuple(g) for g in goals}
    assert len(distinct) >= 5
    assert all(np.linalg.norm(np.array(g) - center) <= 1.0 + TOL for g in distinct)


def test_random_walk_waits_a_draw_from_wait_range_between_moves(sim):
    agent = spawn(sim, ["omni", {"type": "random_walk", "radius": 2.0, "wait_range": [0.5, 0.5]}])
    arrivals, departures = arrivals_and_departures(record(sim, agent, 200))
    arrival_steps = [n for n, _ in arrivals]
    assert len(arrival_steps) >= 3 and departures[0] == 0
    assert [d - a for a, d in zip(arrival_steps, departures[1:], strict=False)] == [5] * (
        len(departures) - 1
    )


def test_random_walk_is_deterministic_per_seed(sim):
    _, first = walk_positions(sim, radius=2.0, wait_range=[0.0, 0.5])
    same = MultiRobotSimulationCore(headless_params(seed=0))
    other = MultiRobotSimulationCore(headless_params(seed=1))
    try:
        _, again = walk_positions(same, radius=2.0, wait_range=[0.0, 0.5])
        _, different = walk_positions(other, radius=2.0, wait_range=[0.0, 0.5])
    finally:
        same.close()
        other.close()
    assert np.array_equal(first, again)
    assert not np.allclose(first, different)


# ----- custom high-level controllers -----------------------------------------------------


def test_custom_high_level_compute_runs_once_per_step_with_dt(sim):
    recorder = StepRecorder()
    agent = spawn(sim, recorder)
    other = StepRecorder()
    spawn(sim, ["omni", other], xyz=(3.0, 0.0, 0.1))
    for _ in range(7):
        sim.step_once()
    assert recorder.calls == [(agent, n, DT) for n in range(7)]
    assert [n for _, n, _ in other.calls] == list(range(7))
    assert all(dt == 0.1 for _, _, dt in recorder.calls)


# ----- woken, not polled ------------------------------------------------------------------


def _walkers(sim):
    robots = []
    for i in range(6):
        x = 5.0 * i
        if i % 2:
            chain = [
                {"type": "omni"},
                {"type": "patrol", "waypoints": [[x + 1.0, 0.0, 0.1], [x, 0.0, 0.1]], "wait": 7.0},
            ]
        else:
            chain = [{"type": "omni"}, {"type": "random_walk", "radius": 2.0, "wait_range": [3, 9]}]
        robots.append(spawn(sim, chain, xyz=(x, 0.0, 0.1)))
    return robots


def test_woken_controllers_match_polling_and_let_idle_steps_skip(sim):
    other = MultiRobotSimulationCore(headless_params())
    try:
        other.fleet.reference_path = True  # every controller called every step
        fast, slow = _walkers(sim), _walkers(other)
        skipped = 0
        while sim.step_count < 600:
            n = sim.skip_idle_steps(600 - sim.step_count)
            skipped += n
            if sim.step_count < 600:
                sim.step_once()
        for _ in range(600):
            other.step_once()
        assert skipped > 100  # the pauses were jumped over
        for a, b in zip(fast, slow, strict=True):
            assert a.get_pose().position.tolist() == b.get_pose().position.tolist()
            assert a.get_pose().orientation.tolist() == b.get_pose().orientation.tolist()
    finally:
        other.close()


def test_a_cached_chain_never_stands_in_for_an_equal_but_invalid_value(sim):
    # True == 1 == 1.0: a chain cached for a valid 1.0 must not answer for True.
    good = {"type": "omni", "max_linear_vel": 1.0}
    Agent.from_mesh(visual_shape=BOX, collision_shape=BOX, sim_core=sim, controller=good)
    Agent.from_mesh(visual_shape=BOX, collision_shape=BOX, sim_core=sim, controller=[good])
    for spec in (
        {"type": "omni", "max_linear_vel": True},
        [{"type": "omni", "max_linear_vel": True}],
    ):
        with pytest.raises(ValueError, match="max_linear_vel"):
            Agent.from_mesh(visual_shape=BOX, collision_shape=BOX, sim_core=sim, controller=spec)
