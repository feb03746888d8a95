"""Per-agent plugins: the battery, plugin management, and plugins from spawn config."""

from __future__ import annotations

import math

import pybullet as p
import pytest

from fleet_async import (
    ActionStatus,
    Agent,
    AgentPlugin,
    AgentSpawnParams,
    BatteryPlugin,
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    WaitAction,
)
from tests.conftest import headless_params

DT = 0.1
TOL = 1e-9
BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def spawn(sim, controller="omni", plugins=None, xyz=(0.0, 0.0, 0.1)):
    params = AgentSpawnParams(
        visual_shape=BOX,
        collision_shape=BOX,
        initial_pose=Pose.from_xyz(*xyz),
        controller=controller,
        plugins=plugins,
    )
    return Agent.from_params(params, sim)


def with_battery(sim, controller="omni", **config):
    return spawn(sim, controller, plugins=[{"type": "battery", "config": config}])


def steps(sim, n):
    for _ in range(n):
        sim.step_once()


class StepCounter(AgentPlugin):
    """Records every on_step call and on_remove."""

    def __init__(self, agent, config=None):
        super().__init__(agent, config)
        self.calls: list[tuple[int, float, float]] = []
        self.removed = 0

    def on_step(self, dt):
        self.calls.append((self.agent.sim_core.step_count, dt, self.agent.get_pose().x))

    def on_remove(self):
        self.removed += 1


# ----- BatteryPlugin config --------------------------------------------------------------


def test_battery_defaults(sim):
    agent = spawn(sim)
    battery = BatteryPlugin(agent)
    assert battery.agent is agent and battery.config == {}
    assert battery.soc == 1.0
    assert battery.drain_per_meter == 0.001
    assert battery.drain_per_second == 0.0001
    assert battery.charge_rate == 0.01
    assert battery.charging is False and battery.distance == 0.0


def test_battery_config_overrides_defaults(sim):
    agent = spawn(sim)
    battery = BatteryPlugin(agent, {"initial_soc": 0.25, "drain_per_meter": 0, "charge_rate": 0.5})
    assert battery.soc == 0.25 and battery.drain_per_meter == 0.0
    assert battery.drain_per_second == 0.0001 and battery.charge_rate == 0.5


@pytest.mark.parametrize(
    ("config", "match"),
    [
        ({"capacity": 100.0}, r"unknown config key\(s\) \['capacity'\]"),
        ({"capacity": 1, "voltage": 2}, r"\['capacity', 'voltage'\]"),
        ({"drain_per_meter": -0.1}, r"BatteryPlugin\.drain_per_meter.*-0\.1"),
        ({"drain_per_second": -1}, r"BatteryPlugin\.drain_per_second"),
        ({"charge_rate": -0.01}, r"BatteryPlugin\.charge_rate"),
        ({"initial_soc": -0.5}, r"BatteryPlugin\.initial_soc"),
        (
            {"initial_soc": 1.5},
            r"BatteryPlugin\.initial_soc: expected a value in \[0, 1\], got 1\.5",
        ),
        ({"charge_rate": math.nan}, r"BatteryPlugin\.charge_rate"),
        ({"drain_per_meter": math.inf}, r"BatteryPlugin\.drain_per_meter"),
        ({"charge_rate": "fast"}, r"BatteryPlugin\.charge_rate.*'fast'"),
        ({"initial_soc": True}, r"BatteryPlugin\.initial_soc"),
    ],
)
def test_battery_rejects_bad_config(sim, config, match):
    agent = spawn(sim)
    with pytest.raises(ValueError, match=match):
        BatteryPlugin(agent, config)


def test_unknown_key_lists_the_valid_ones(sim):
    agent = spawn(sim)
    with pytest.raises(ValueError, match="capacity") as info:
        BatteryPlugin(agent, {"capacity": 1.0})
    for key in ("initial_soc", "drain_per_meter", "drain_per_second", "charge_rate"):
        assert key in str(info.value)


def test_soc_is_one_without_a_battery(sim):
    agent = spawn(sim)
    assert agent.battery_plugin is None and agent.battery_soc == 1.0
    agent.set_charging(True)  # no-op without a battery
    assert agent.is_charging is False
    agent.set_goal_pose(Pose.from_xyz(2.0, 0.0, 0.1))
    steps(sim, 20)
    assert agent.battery_soc == 1.0


# ----- drain -----------------------------------------------------------------------------


def test_drain_by_distance_over_exactly_ten_metres(sim):
    agent = with_battery(sim, drain_per_meter=0.01, drain_per_second=0.0)
    agent.set_goal_pose(Pose.from_xyz(10.0, 0.0, 0.1))
    for _ in range(500):
        sim.step_once()
        if not agent.is_moving:
            break
    assert agent.get_pose().position.tolist() == [10.0, 0.0, 0.1]
    assert agent.battery_plugin.distance == pytest.approx(10.0, abs=TOL)
    assert agent.battery_soc == pytest.approx(0.9, abs=TOL)
    # Standing still afterwards costs nothing.
    soc = agent.battery_soc
    steps(sim, 10)
    assert agent.battery_soc == soc


def test_turning_in_place_is_not_distance(sim):
    agent = with_battery(sim, "differential", drain_per_meter=1.0, drain_per_second=0.0)
    agent.set_goal_pose(Pose.from_euler(0.0, 0.0, 0.1, yaw=math.pi / 2))
    steps(sim, 30)
    assert agent.get_pose().yaw == pytest.approx(math.pi / 2, abs=TOL) and not agent.is_moving
    assert agent.battery_plugin.distance == 0.0 and agent.battery_soc == 1.0


def test_drain_by_time_while_idle(sim):
    agent = with_battery(sim, drain_per_meter=0.5, drain_per_second=0.01)
    steps(sim, 10)
    assert agent.battery_soc == pytest.approx(1.0 - 0.01 * 1.0, abs=TOL)
    steps(sim, 15)
    assert agent.battery_soc == pytest.approx(1.0 - 0.01 * 2.5, abs=TOL)
    assert agent.battery_plugin.distance == 0.0


def test_soc_never_drops_below_zero(sim):
    agent = with_battery(sim, initial_soc=0.05, drain_per_second=0.1)
    steps(sim, 5)
    assert agent.battery_soc == pytest.approx(0.0, abs=TOL)
    steps(sim, 5)
    assert agent.battery_soc == 0.0


# ----- charging --------------------------------------------------------------------------


def test_charging_raises_soc_at_charge_rate_and_clamps_at_one(sim):
    agent = with_battery(sim, initial_soc=0.5, charge_rate=0.1, drain_per_second=0.0)
    agent.set_charging(True)
    assert agent.is_charging and agent.battery_plugin.charging
    history = []
    for _ in range(55):
        sim.step_once()
        history.append(agent.battery_soc)
    for k, soc in enumerate(history[:50], start=1):
        assert soc == pytest.approx(min(1.0, 0.5 + 0.1 * DT * k), abs=TOL)
    assert max(history) <= 1.0 and history[50:] == [1.0] * 5
    agent.set_charging(False)
    assert not agent.is_charging


def test_charging_and_drain_add_up(sim):
    agent = with_battery(sim, initial_soc=0.5, charge_rate=0.05, drain_per_second=0.01)
    agent.set_charging(True)
    steps(sim, 10)
    assert agent.battery_soc == pytest.approx(0.5 + (0.05 - 0.01) * 1.0, abs=TOL)
    agent.set_charging(False)
    steps(sim, 10)
    assert agent.battery_soc == pytest.approx(0.5 + 0.04 - 0.01, abs=TOL)


def test_charge_wait_action_charges_for_exactly_its_duration(sim):
    agent = with_battery(sim, initial_soc=0.5, charge_rate=0.02, drain_per_second=0.0)
    wait = WaitAction(duration=2.0, action_type="charge")
    agent.add_action(wait)
    charging = []
    for _ in range(30):
        sim.step_once()
        charging.append(agent.is_charging)
    # Charging through the 20 steps covering 0.0 .. 2.0 s; at 2.0 s (after the 20th step)
    # the wait is over, so the state seen after each step is on 19 times, then off.
    assert charging == [True] * 19 + [False] * 11
    assert wait.status is ActionStatus.COMPLETED
    assert wait.start_time == 0.0 and wait.end_time == pytest.approx(2.0, abs=TOL)
    assert agent.battery_soc - 0.5 == pytest.approx(2.0 * 0.02, abs=TOL)


def test_idle_wait_action_does_not_charge(sim):
    agent = with_battery(sim, initial_soc=0.5, drain_per_second=0.0)
    agent.add_action(WaitAction(duration=1.0))
    sim.step_once()
    assert not agent.is_charging
    steps(sim, 15)
    assert agent.battery_soc == 0.5


@pytest.mark.parametrize("how", ["cancel", "clear_actions"])
def test_cancelling_a_running_charge_wait_stops_charging(sim, how):
    agent = with_battery(sim, initial_soc=0.5, charge_rate=0.02, drain_per_second=0.0)
    wait = WaitAction(duration=5.0, action_type="charge")
    agent.add_action(wait)
    steps(sim, 3)
    assert agent.is_charging and wait.status is ActionStatus.IN_PROGRESS
    if how == "cancel":
        wait.cancel()
    else:
        agent.clear_actions()
    assert not agent.is_charging and wait.status is ActionStatus.CANCELLED
    assert wait.end_time == pytest.approx(0.3, abs=TOL)
    soc = agent.battery_soc
    assert soc == pytest.approx(0.5 + 3 * DT * 0.02, abs=TOL)
    steps(sim, 10)
    assert agent.battery_soc == soc and not agent.is_charging


# ----- plugin management -----------------------------------------------------------------


def test_add_plugin_rejects_a_plugin_bound_to_another_agent(sim):
    agent = spawn(sim)
    other = spawn(sim, xyz=(2.0, 0.0, 0.1))
    foreign = BatteryPlugin(other, {"initial_soc": 0.3})
    with pytest.raises(ValueError, match="add_plugin: BatteryPlugin is bound to"):
        agent.add_plugin(foreign)
    assert agent.plugins == [] and agent.battery_soc == 1.0


def test_add_plugin_steps_it_once_per_step_after_motion(sim):
    agent = spawn(sim)
    counter = StepCounter(agent)
    agent.add_plugin(counter)
    assert agent.plugins == [counter]
    agent.set_goal_pose(Pose.from_xyz(2.0, 0.0, 0.1))
    steps(sim, 4)
    assert [(n, dt) for n, dt, _ in counter.calls] == [(n, DT) for n in range(4)]
    # It sees the pose this step's motion produced, not the previous one.
    assert counter.calls[0][2] > 0.0
    assert [x for _, _, x in counter.calls] == sorted({x for _, _, x in counter.calls})


def test_remove_plugin_by_class(sim):
    agent = with_battery(sim, initial_soc=0.4)
    assert agent.battery_soc == 0.4
    assert agent.remove_plugin(BatteryPlugin) is True
    assert agent.plugins == [] and agent.battery_plugin is None and agent.battery_soc == 1.0
    assert agent.remove_plugin(BatteryPlugin) is False


def test_remove_plugin_by_instance(sim):
    agent = with_battery(sim)
    battery = agent.battery_plugin
    first, second = StepCounter(agent), StepCounter(agent)
    agent.add_plugin(first)
    agent.add_plugin(second)
    sim.step_once()
    assert agent.remove_plugin(second) is True
    assert agent.plugins == [battery, first] and second.removed == 1 and first.removed == 0
    sim.step_once()
    assert len(first.calls) == 2 and len(second.calls) == 1
    assert agent.remove_plugin(second) is False
    assert agent.remove_plugin(StepCounter) is True and agent.plugins == [battery]


def test_get_plugin(sim):
    agent = with_battery(sim)
    battery = agent.battery_plugin
    counter = StepCounter(agent)
    agent.add_plugin(counter)
    assert agent.get_plugin(BatteryPlugin) is battery
    assert agent.get_plugin(StepCounter) is counter
    assert agent.get_plugin(AgentPlugin) is battery  # first in order added
    agent.remove_plugin(battery)
    assert agent.get_plugin(BatteryPlugin) is None
    assert agent.get_plugin(AgentPlugin) is counter


def test_removing_the_agent_tells_its_plugins(sim):
    agent = spawn(sim)
    counter = StepCounter(agent)
    agent.add_plugin(counter)
    sim.step_once()
    sim.remove_object(agent)
    assert counter.removed == 1
    steps(sim, 3)
    assert len(counter.calls) == 1


# ----- plugins from spawn config ---------------------------------------------------------


def test_battery_from_spawn_params(sim):
    agent = with_battery(sim, initial_soc=0.8, drain_per_second=0.01, drain_per_meter=0.0)
    battery = agent.battery_plugin
    assert type(battery) is BatteryPlugin and battery.agent is agent
    assert agent.plugins == [battery] and battery.config == {
        "initial_soc": 0.8,
        "drain_per_second": 0.01,
        "drain_per_meter": 0.0,
    }
    steps(sim, 10)
    assert agent.battery_soc == pytest.approx(0.8 - 0.01, abs=TOL)


def test_battery_from_agent_dict(sim):
    agent = Agent.from_dict(
        {
            "visual_shape": {"shape_type": "box", "half_extents": [0.2, 0.2, 0.1]},
            "plugins": [{"type": "battery", "config": {"initial_soc": 0.6}}],
        },
        sim,
    )
    assert isinstance(agent.battery_plugin, BatteryPlugin) and agent.battery_soc == 0.6


def test_plugin_entry_without_config_uses_defaults(sim):
    agent = spawn(sim, plugins=[{"type": "battery"}])
    assert agent.battery_soc == 1.0 and agent.battery_plugin.charge_rate == 0.01


def test_plugin_from_a_class_path(sim):
    agent = spawn(
        sim,
        plugins=[
            {"class": f"{StepCounter.__module__}.StepCounter", "config": {"label": "x"}},
            {
                "class": "fleet_async.core.agents.agent_plugins.BatteryPlugin",
                "config": {"initial_soc": 0.7},
            },
        ],
    )
    counter, battery = agent.plugins
    assert type(counter) is StepCounter and counter.config == {"label": "x"}
    assert type(battery) is BatteryPlugin and agent.battery_soc == 0.7
    steps(sim, 2)
    assert [n for n, _, _ in counter.calls] == [0, 1]


@pytest.mark.parametrize(
    ("entry", "match"),
    [
        ({"type": "solar"}, r"plugins\[0\]\.type: unknown plugin 'solar'; known: \[.*'battery'"),
        (
            {"type": "battery", "class": "fleet_async.core.agents.agent_plugins.BatteryPlugin"},
            r"plugins\[0\]: give exactly one of 'type' or 'class'",
        ),
        ({"config": {}}, r"plugins\[0\]: give exactly one of 'type' or 'class'"),
        ({"type": "battery", "settings": {}}, r"plugins\[0\]: unknown key\(s\) \['settings'\]"),
        (
            {"class": "fleet_async.core.geometry.pose.Pose"},
            r"plugins\[0\]\.class: 'fleet_async\.core\.geometry\.pose\.Pose' is not an AgentPlugin",
        ),
        ({"type": "battery", "config": {"capacity": 1}}, "capacity"),
    ],
)
def test_bad_plugin_entry_is_a_value_error_naming_it(sim, entry, match):
    with pytest.raises(ValueError, match=match):
        spawn(sim, plugins=[entry])


def test_bad_plugin_entry_is_named_by_its_index(sim):
    with pytest.raises(ValueError, match=r"plugins\[1\]\.type: unknown plugin 'solar'"):
        spawn(sim, plugins=[{"type": "battery"}, {"type": "solar"}])


def test_plugins_must_be_a_list_of_mappings():
    with pytest.raises(ValueError, match=r"AgentSpawnParams\.plugins"):
        AgentSpawnParams(plugins={"type": "battery"})
    with pytest.raises(ValueError, match=r"AgentSpawnParams\.plugins"):
        AgentSpawnParams(plugins=["battery"])


def test_rejected_plugin_entry_leaves_no_agent_behind(sim):
    bodies = p.getNumBodies(physicsClientId=sim.client)
    with pytest.raises(ValueError, match="solar"):
        spawn(sim, plugins=[{"type": "solar"}])
    assert sim.agents == []
    assert p.getNumBodies(physicsClientId=sim.client) == bodies


# ----- the battery bank: one formula, one numpy pass --------------------------------------


def _battery_fleet(sim, reference):
    sim.fleet.reference_path = reference
    agents = []
    for i in range(6):
        config = {
            "initial_soc": 0.3 + 0.1 * i,
            "drain_per_meter": 0.003,
            "drain_per_second": 0.0007 * i,
            "charge_rate": 0.02,
            "discharge_rate": 0.001 * (i % 2),
            "idle_rate": 0.0005 * (i % 3),
        }
        agent = with_battery(sim, "differential" if i % 2 else "omni", **config)
        agent.set_pose(Pose.from_xyz(3.0 * i, 0.0, 0.1))
        agents.append(agent)
    return agents


def _battery_run(sim, reference):
    agents = _battery_fleet(sim, reference)
    trace = []
    for k in range(120):
        if k % 40 == 0:
            for i, agent in enumerate(agents):
                agent.set_goal_pose(Pose.from_xyz(3.0 * i + (k % 80) / 20.0, 1.0 + i, 0.1))
                agent.set_charging(bool((i + k // 40) % 2))
        sim.step_once()
        trace.append(
            [(a.battery_soc, a.battery_plugin.used, a.battery_plugin.distance) for a in agents]
        )
    return trace


@pytest.fixture
def other_sim():
    core = MultiRobotSimulationCore(headless_params())
    yield core
    core.close()


def test_numpy_pass_and_per_robot_reference_give_the_same_bits(sim, other_sim):
    vector = _battery_run(sim, reference=False)
    reference = _battery_run(other_sim, reference=True)
    assert vector == reference
    assert vector[0] != vector[-1]


def test_batteries_do_not_block_idle_skipping_and_a_skipped_span_equals_stepping(sim, other_sim):
    def standing(s):
        agents = _battery_fleet(s, reference=False)
        agents[1].set_charging(True)
        s.step_once()
        return agents

    stepped, skipped = standing(sim), standing(other_sim)
    other = other_sim
    assert other.idle_steps(500) == 500
    other.skip_steps(500)
    steps(sim, 500)
    assert [(a.battery_soc, a.battery_plugin.used) for a in stepped] == [
        (a.battery_soc, a.battery_plugin.used) for a in skipped
    ]
    assert stepped[2].battery_soc < 0.5 and stepped[1].battery_soc == 1.0


def test_incumbent_keys_discharge_rate_while_moving_idle_rate_while_standing(sim):
    agent = with_battery(
        sim, drain_per_meter=0.0, drain_per_second=0.0, discharge_rate=0.01, idle_rate=0.002
    )
    steps(sim, 10)  # standing 1 s
    assert agent.battery_soc == pytest.approx(1.0 - 0.002, abs=TOL)
    agent.set_goal_pose(Pose.from_xyz(0.5, 0.0, 0.1))
    moving = 0
    while True:
        sim.step_once()
        moving += 1  # the step it arrives in is driven, too
        if not agent.is_moving:
            break
    assert agent.battery_soc == pytest.approx(1.0 - 0.002 - 0.01 * DT * moving, abs=1e-6)
    agent.set_charging(True)  # charging: neither rate applies
    soc = agent.battery_soc
    steps(sim, 5)
    assert agent.battery_soc == pytest.approx(soc + 0.01 * 0.5, abs=TOL)
