"""Scenarios: a whole simulation from one mapping or YAML file (core/scenario/build.py)."""

from __future__ import annotations

import math
from pathlib import Path as FsPath
from typing import ClassVar

import numpy as np
import pybullet as p
import pytest
import yaml

from fleet_async import (
    Agent,
    AgentManager,
    DifferentialController,
    MultiRobotSimulationCore,
    OmniController,
    PatrolController,
    SimEvents,
    SimObject,
    SimObjectManager,
    SimPlugin,
)
from fleet_async.core.base.config_utils import load_yaml_config
from fleet_async.core.devices import Device
from fleet_async.core.managers import sim_object_manager as managers
from fleet_async.core.scenario import build as scenario
from tests.conftest import headless_params

DATA = FsPath(__file__).resolve().parent.parent / "data" / "scenarios"
EXAMPLES = sorted((FsPath(__file__).resolve().parents[2] / "examples" / "scenarios").glob("*.yaml"))
HEADLESS = {"gui": False, "monitor": False, "target_rtf": 0.0, "timestep": 0.1}
BOX = {"shape_type": "box", "half_extents": [0.2, 0.2, 0.1]}


# ----- helpers and classes the scenarios refer to by dotted path ------------------------------


class Forklift(Agent):
    """A custom entity class, registered through ``entity_classes`` by its dotted path."""


class CountingPlugin(SimPlugin):
    """Counts its steps; remembers how many agents existed when it was registered."""

    def on_init(self) -> None:
        self.agents_at_init = len(self.sim_core.agents)
        self.steps = 0

    def on_step(self, dt: float) -> None:
        self.steps += 1


class SpySim(MultiRobotSimulationCore):
    """Remembers the client id of every simulation built, and the world it was asked to load."""

    clients: ClassVar[list[int]] = []
    worlds: ClassVar[list[tuple[dict, object]]] = []

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        SpySim.clients.append(self.client)

    def load_world(self, world_config, skip_models=None, *, base_dir=None):
        SpySim.worlds.append((world_config, base_dir))
        if world_config.get("fail"):
            raise ValueError("world_file 'missing.world' not found")
        return [SimObject.from_mesh(BOX, BOX, sim_core=self, name="wall")]


def nested(**sections):
    return {"simulation": dict(HEADLESS), **sections}


def robot(**kw):
    return {"visual_shape": BOX, "collision_shape": BOX, "controller": "omni", **kw}


def write(tmp_path, config, name="scenario.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    return path


def positions(objects):
    return [obj.get_pose().position.tolist() for obj in objects]


def connected(client):
    return p.getConnectionInfo(physicsClientId=client)["isConnected"] == 1


def run_until_idle(sim, agents, max_steps=2000):
    for _ in range(max_steps):
        if all(a.is_action_queue_empty() and not a.is_moving for a in agents):
            return
        sim.step_once()
    raise AssertionError("agents did not finish their actions")


@pytest.fixture
def build():
    """``from_dict`` / ``from_yaml`` whose simulations are closed at teardown."""
    built = []

    def make(config_or_path, cls=MultiRobotSimulationCore, **kwargs):
        if isinstance(config_or_path, FsPath):
            sim = cls.from_yaml(config_or_path)
        else:
            sim = cls.from_dict(config_or_path, **kwargs)
        built.append(sim)
        return sim

    yield make
    for sim in built:
        sim.close()


@pytest.fixture(autouse=True)
def clean_registries():
    """Undo entity-class and plugin registrations, and reset the spy's records."""
    entities, plugins = dict(managers.ENTITY_REGISTRY), dict(scenario.SIM_PLUGIN_REGISTRY)
    SpySim.clients, SpySim.worlds = [], []
    yield
    managers.ENTITY_REGISTRY.clear()
    managers.ENTITY_REGISTRY.update(entities)
    scenario.SIM_PLUGIN_REGISTRY.clear()
    scenario.SIM_PLUGIN_REGISTRY.update(plugins)


# ----- layouts --------------------------------------------------------------------------------


def test_flat_legacy_layout(build):
    sim = build(DATA / "flat_legacy.yaml")
    assert (sim.params.timestep, sim.params.seed, sim.params.enable_floor) == (0.05, 7, True)
    assert sim.sim_objects == []


def test_nested_layout_simulation_section(build):
    sim = build({"simulation": {**HEADLESS, "timestep": 0.02}})
    assert sim.params.timestep == 0.02
    assert sim.params.enable_floor is True


def test_unknown_section_names_the_nearest_section_and_the_file(tmp_path):
    path = write(tmp_path, nested(entites=[]), "typo_section.yaml")
    with pytest.raises(ValueError, match="unknown key 'entites'") as info:
        MultiRobotSimulationCore.from_yaml(path)
    message = str(info.value)
    assert "typo_section.yaml" in message
    assert "did you mean 'entities'?" in message


def test_flat_layout_with_a_misspelt_section_suggests_the_section(tmp_path):
    path = write(tmp_path, {"gui": False, "entites": []}, "flat_typo.yaml")
    with pytest.raises(ValueError, match=r"flat_typo\.yaml.*'entites'.*section 'entities'"):
        MultiRobotSimulationCore.from_yaml(path)


def test_a_setting_at_the_top_of_the_nested_layout_belongs_under_simulation(tmp_path):
    path = write(tmp_path, {**nested(entities=[]), "timestep": 0.5}, "mixed.yaml")
    with pytest.raises(ValueError, match=r"mixed\.yaml.*'timestep'.*under 'simulation:'"):
        MultiRobotSimulationCore.from_yaml(path)


# ----- entities -------------------------------------------------------------------------------


def test_entity_poses_position_yaw_orientation_and_rpy(build):
    quarter = [0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)]
    sim = build(
        nested(
            entities=[
                robot(name="r", pose=[1.0, 2.0, 0.1], yaw=math.pi / 2),
                {
                    "type": "sim_object",
                    "name": "q",
                    "visual_shape": BOX,
                    "pose": {"position": [3.0, 0.0, 0.1], "orientation": quarter},
                },
                {
                    "type": "sim_object",
                    "name": "e",
                    "visual_shape": BOX,
                    "pose": {"position": [0.0, 3.0, 0.1], "rpy": [0.0, 0.0, math.pi / 2]},
                },
            ]
        )
    )
    r, q, e = sim.sim_objects
    assert isinstance(r, Agent) and type(q) is SimObject and not q.is_agent
    assert positions([r, q, e]) == [[1.0, 2.0, 0.1], [3.0, 0.0, 0.1], [0.0, 3.0, 0.1]]
    for obj in (r, q, e):
        assert obj.get_pose().yaw == pytest.approx(math.pi / 2, abs=1e-12)


def test_count_based_grid(build):
    sim = build(
        nested(
            entities=[
                robot(
                    name="g",
                    yaw=math.pi,
                    grid={"count": 5, "columns": 2, "spacing": [2.0, 3.0], "offset": [1, 1, 0.1]},
                )
            ]
        )
    )
    assert positions(sim.agents) == [
        [1.0, 1.0, 0.1], [3.0, 1.0, 0.1],
        [1.0, 4.0, 0.1], [3.0, 4.0, 0.1],
        [1.0, 7.0, 0.1],
    ]  # fmt: skip
    assert all(abs(a.get_pose().yaw) == pytest.approx(math.pi) for a in sim.agents)


def test_range_based_grid_with_batch_controller_shorthand(build):
    sim = build(
        nested(
            entities=[
                robot(
                    controller="differential",
                    batch_controller="batch_omni",
                    grid={
                        "x_min": 0,
                        "x_max": 2,
                        "y_min": 0,
                        "y_max": 1,
                        "spacing": [1.0, 2.0, 0.0],
                        "offset": [0.0, 0.0, 0.1],
                    },
                ),
                robot(controller="differential", pose=[9.0, 9.0, 0.1]),
            ]
        )
    )
    grid, single = sim.agents[:6], sim.agents[6]
    assert positions(grid) == [
        [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [2.0, 0.0, 0.1],
        [0.0, 2.0, 0.1], [1.0, 2.0, 0.1], [2.0, 2.0, 0.1],
    ]  # fmt: skip
    assert all(type(a.controller) is OmniController for a in grid)  # the batch mode won
    assert type(single.controller) is DifferentialController


def test_named_managers_of_both_types(build):
    sim = build(
        nested(
            managers=[
                {
                    "name": "fleet",
                    "fleet_controller": {"max_linear_vel": 2.5},
                    "update_frequency": 5,
                },
                {"name": "crates", "type": "sim_object"},
            ],
            entities=[
                robot(manager="fleet", grid={"count": 3, "spacing": [1, 1], "offset": [0, 0, 0.1]}),
                robot(name="solo", manager="fleet", pose=[5.0, 5.0, 0.1]),
                {"type": "sim_object", "name": "crate", "visual_shape": BOX, "manager": "crates"},
                robot(name="free", pose=[8.0, 0.0, 0.1]),
            ],
        )
    )
    fleet, crates = sim.get_manager("fleet"), sim.get_manager("crates")
    assert isinstance(fleet, AgentManager) and fleet.update_frequency == 5.0
    assert type(crates) is SimObjectManager
    assert [a.name for a in fleet.objects] == [None, None, None, "solo"]
    assert [a.controller_params.max_linear_vel for a in fleet.objects] == [2.5] * 4
    assert sim.agents[-1].controller_params.max_linear_vel != 2.5  # not in the fleet
    crate = crates.objects[0]
    assert crate.name == "crate"
    sim.remove_object(crate)  # the manager is registered, so it follows removals
    assert crates.objects == []


def test_custom_entity_class_by_dotted_path(build):
    sim = build(
        nested(
            entity_classes={"forklift": f"{__name__}.Forklift"},
            managers=[{"name": "lifts", "object_class": "forklift"}],
            entities=[
                robot(type="forklift", name="f0", pose=[0.0, 0.0, 0.1]),
                robot(type="forklift", manager="lifts", grid={"count": 2, "spacing": [2, 0]}),
                robot(
                    type="forklift",
                    grid={"count": 2, "columns": 1, "spacing": [0, 2], "offset": [5, 0]},
                ),
            ],
        )
    )
    assert all(type(a) is Forklift for a in sim.agents)
    assert positions(sim.agents) == [
        [0.0, 0.0, 0.1], [0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [5.0, 0.0, 0.0], [5.0, 2.0, 0.0]
    ]  # fmt: skip
    assert sim.get_manager("lifts").objects == sim.agents[1:3]


def test_plugins_by_class_path_and_by_registered_name(build):
    scenario.register_sim_plugin("counter", CountingPlugin)
    sim = build(
        nested(
            entities=[robot(pose=[0.0, 0.0, 0.1]), robot(pose=[1.0, 0.0, 0.1])],
            plugins=[
                {
                    "class": f"{__name__}.CountingPlugin",
                    "config": {"label": "slow"},
                    "frequency": 2,
                },
                {"type": "counter"},
            ],
        )
    )
    slow, every = sim.plugins
    assert slow.config == {"label": "slow"} and every.config == {}
    assert (slow.agents_at_init, every.agents_at_init) == (2, 2)  # plugins come last
    for _ in range(20):  # sim times 0.0 .. 1.9
        sim.step_once()
    assert (slow.steps, every.steps) == (3, 20)  # 2 Hz: at 0.5, 1.0 and 1.5 s


# ----- actions --------------------------------------------------------------------------------


def test_move_and_wait_actions_run_to_completion(build):
    sim = build(
        nested(
            entities=[
                robot(
                    name="mover",
                    pose=[0.0, 0.0, 0.1],
                    controller={"type": "omni", "max_linear_vel": 1.0, "max_linear_accel": 10.0},
                    actions=[
                        {"type": "move", "path": [[2.0, 0.0, 0.1], [2.0, 2.0, 0.1]]},
                        {"type": "wait", "duration": 1.5},
                    ],
                )
            ]
        )
    )
    done = []
    sim.events.on(SimEvents.ACTION_COMPLETED, lambda agent, action: done.append(action))
    (mover,) = sim.agents
    assert mover.get_action_queue_size() == 2
    run_until_idle(sim, [mover])
    assert [type(a).__name__ for a in done] == ["MoveAction", "WaitAction"]
    assert mover.get_pose().position.tolist() == pytest.approx([2.0, 2.0, 0.1], abs=1e-9)
    assert done[1].get_duration() == pytest.approx(1.5)


def test_pick_and_drop_actions_carry_a_box(build):
    sim = build(
        nested(
            entities=[
                {"type": "sim_object", "name": "box", "visual_shape": BOX, "pose": [3, 0, 0.1]},
                robot(
                    pose=[0.0, 0.0, 0.1],
                    actions=[
                        {
                            "type": "pick",
                            "target_position": [3.0, 0.0, 0.1],
                            "attach_relative_pose": {"position": [0.0, 0.0, 0.2]},
                        },
                        {"type": "move", "path": [[0.0, 1.0, 0.1]]},
                        {"type": "drop", "drop_pose": [0.0, 3.0, 0.1]},
                    ],
                ),
            ]
        )
    )
    box, carrier = sim.sim_objects
    failed = []
    sim.events.on(SimEvents.ACTION_FAILED, lambda agent, action: failed.append(action))
    run_until_idle(sim, [carrier])
    assert failed == []
    assert not box.is_attached()
    assert box.get_pose().position.tolist() == pytest.approx([0.0, 3.0, 0.1], abs=1e-9)


# ----- files ----------------------------------------------------------------------------------


def test_relative_paths_resolve_next_to_the_yaml(build, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # nothing relative to the working directory
    sim = build(DATA / "relative_paths.yaml")
    bot, crate = sim.sim_objects
    assert bot.urdf_path == str((DATA / "models" / "crate_bot.urdf").resolve())
    assert bot.get_pose().position.tolist() == [1.0, 2.0, 0.1]
    lo, hi = p.getAABB(crate.body_id, physicsClientId=sim.client)
    assert np.subtract(hi, lo) == pytest.approx([0.5, 0.5, 0.5], abs=0.01)  # unit cube * 0.5


@pytest.mark.parametrize(
    ("entity", "tried"),
    [
        ({"urdf_path": "models/nope.urdf"}, "entities[0].urdf_path"),
        (
            {
                "type": "sim_object",
                "visual_shape": {"shape_type": "mesh", "mesh_path": "meshes/nope.obj"},
            },
            "entities[0].visual_shape.mesh_path",
        ),
    ],
)
def test_a_missing_file_names_the_paths_tried(tmp_path, entity, tried):
    path = write(tmp_path, nested(entities=[entity]), "missing_file.yaml")
    relative = entity.get("urdf_path") or entity["visual_shape"]["mesh_path"]
    with pytest.raises(FileNotFoundError) as info:
        MultiRobotSimulationCore.from_yaml(path)
    message = str(info.value)
    assert "missing_file.yaml" in message and tried in message
    assert str(tmp_path / relative) in message


# ----- malformed scenarios ----------------------------------------------------------------------


MALFORMED = [
    ({"simulation": {"timestep": "fast"}}, ["simulation.timestep", "'fast'", "expected float"]),
    (nested(entities={"a": 1}), ["entities: expected a list", "dict"]),
    (nested(entities=["robot"]), ["entities[0]: expected a mapping", "'robot'"]),
    (nested(entities=[{"urdf_pth": "x"}]), ["entities[0]", "'urdf_pth'", "'urdf_path'"]),
    (nested(entities=[{}, {"gird": {}}]), ["entities[1]", "'gird'", "did you mean 'grid'"]),
    (nested(entities=[robot(mass="heavy")]), ["entities[0]", "mass", "'heavy'", "float"]),
    (nested(entities=[{"type": "forklfit"}]), ["entities[0].type", "'forklfit'", "known types"]),
    (
        nested(entities=[robot(grid={"count": 3, "spcing": [1, 1]})]),
        ["entities[0].grid", "'spcing'", "did you mean 'spacing'"],
    ),
    (
        nested(
            entities=[
                robot(
                    grid={
                        "x_min": 0,
                        "x_max": 1,
                        "y_min": 0,
                        "y_max": 0,
                        "spacing": [1, 1],
                        "offst": [0, 0],
                    }
                )
            ]
        ),
        ["entities[0].grid", "'offst'", "did you mean 'offset'"],
    ),
    (
        nested(entities=[robot(pose=[0, 0, 0], grid={"count": 2})]),
        ["entities[0]", "'pose' cannot be combined with 'grid'"],
    ),
    (
        nested(entities=[{"type": "sim_object", "actions": []}]),
        ["entities[0].actions", "only agents"],
    ),
    (
        nested(entities=[robot(actions=[{"type": "fly"}])]),
        [
            "entities[0].actions[0].type",
            "'fly'",
            "['drop', 'joint', 'move', 'pick', 'pose', 'wait']",
        ],
    ),
    (
        nested(entities=[robot(actions=[{"type": "move", "pth": [[1, 0, 0]]}])]),
        ["entities[0].actions[0]", "'pth'", "did you mean 'path'"],
    ),
    (
        nested(entities=[robot(actions=[{"type": "wait", "duration": "long"}])]),
        ["entities[0].actions[0].duration", "'long'", "expected float"],
    ),
    (
        nested(entities=[robot(actions=[{"type": "drop", "drop_pose": [1, 2]}])]),
        ["entities[0].actions[0].drop_pose", "[1, 2]"],
    ),
    (
        nested(entities=[robot(manager="fleet")]),
        ["entities[0].manager", "'fleet'", "declared managers: []"],
    ),
    (
        nested(
            managers=[{"name": "crates", "type": "sim_object"}],
            entities=[robot(manager="crates", batch_controller="batch_omni")],
        ),
        ["entities[0]", "'manager' or 'batch_controller'"],
    ),
    (
        nested(
            managers=[{"name": "fleet"}],
            entities=[{"type": "sim_object", "visual_shape": BOX, "manager": "fleet"}],
        ),
        ["entities[0].manager", "'fleet' is an agent manager"],
    ),
    (nested(managers={"fleet": {}}), ["managers: expected a list", "dict"]),
    (nested(managers=[{"type": "agent"}]), ["managers[0].name", "expected a name"]),
    (nested(managers=[{"name": "a", "type": "robots"}]), ["managers[0].type", "'robots'"]),
    (
        nested(managers=[{"name": "a", "batch_controler": "batch_omni"}]),
        ["managers[0]", "'batch_controler'", "did you mean 'batch_controller'"],
    ),
    (nested(managers=[{"name": "a"}, {"name": "a"}]), ["managers[1].name", "declared twice"]),
    (
        nested(managers=[{"name": "a", "batch_controller": "batch_warp"}]),
        ["managers[0]", "'batch_warp'"],
    ),
    (
        nested(managers=[{"name": "a", "object_class": "no_such_module.Lift"}]),
        ["managers[0].object_class", "no_such_module"],
    ),
    (nested(entity_classes={"lift": 3}), ["entity_classes.lift", "expected a dotted path"]),
    (
        nested(entity_classes={"lift": "no_such_module.Lift"}),
        ["entity_classes.lift", "no_such_module"],
    ),
    (nested(plugins=[{"type": "nope"}]), ["plugins[0].type", "'nope'"]),
    (nested(plugins=[{"class": "no_such_module.Plugin"}]), ["plugins[0].class", "no_such_module"]),
    (
        nested(plugins=[{"class": f"{__name__}.CountingPlugin", "frequncy": 2}]),
        ["plugins[0]", "'frequncy'", "did you mean 'frequency'"],
    ),
    (
        nested(plugins=[{"class": f"{__name__}.CountingPlugin", "frequency": -1}]),
        ["plugins[0].frequency", "-1", "> 0"],
    ),
    (nested(world=[1]), ["world: expected a mapping", "list"]),
]


@pytest.mark.parametrize(("config", "fragments"), MALFORMED)
def test_malformed_scenarios_name_the_key_the_value_and_the_file(tmp_path, config, fragments):
    path = write(tmp_path, config, "bad_scenario.yaml")
    with pytest.raises(ValueError, match=r"bad_scenario\.yaml") as info:
        MultiRobotSimulationCore.from_yaml(path)
    message = str(info.value)
    assert message.startswith(str(path)), message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def test_yaml_syntax_errors_name_the_line(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text("simulation:\n  gui: [false\n")
    with pytest.raises(ValueError, match=r"broken\.yaml, line \d+, column \d+"):
        MultiRobotSimulationCore.from_yaml(path)


@pytest.mark.parametrize(
    ("config", "match"),
    [
        (nested(entities=[robot(manager="nowhere")]), "'nowhere'"),  # while planning entities
        (nested(entities=[robot(), robot(controller={"type": "warp"})]), "'warp'"),  # spawning
        (nested(world={"fail": True}), r"world: world_file 'missing\.world'"),  # load_world
        (nested(managers=[{"name": "a", "batch_controller": "batch_warp"}]), "'batch_warp'"),
    ],
)
def test_a_failing_scenario_leaves_no_pybullet_connection(config, match):
    with pytest.raises(ValueError, match=match):
        SpySim.from_dict(config)
    (client,) = SpySim.clients
    assert client >= 0 and not connected(client)


# ----- world ----------------------------------------------------------------------------------


def test_world_section_is_loaded_and_turns_the_floor_off(build, tmp_path):
    world = {"world_file": "maps/office.world"}
    sim = build(write(tmp_path, nested(world=world)), cls=SpySim)
    assert SpySim.worlds == [(world, tmp_path)]
    assert sim.params.enable_floor is False
    assert [o.name for o in sim.sim_objects] == ["wall"]
    assert p.getNumBodies(physicsClientId=sim.client) == 1  # the wall, no floor plane


def test_a_real_world_section_resolves_next_to_the_yaml(build, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    sim = build(DATA / "world_mesh_dir.yaml")
    crate, bot = sim.sim_objects
    assert (crate.name, crate.collision_mode.value, bot.name) == ("crate", "static", "bot")
    assert p.getNumBodies(physicsClientId=sim.client) == 2  # no floor plane


def test_an_explicit_enable_floor_wins_over_the_world_section(build):
    sim = build(
        {"simulation": {**HEADLESS, "enable_floor": True}, "world": {"world_file": "x.world"}},
        cls=SpySim,
    )
    assert sim.params.enable_floor is True
    assert p.getNumBodies(physicsClientId=sim.client) == 2  # floor and wall


# ----- spawn_robots_from_config ---------------------------------------------------------------


def test_spawn_robots_from_config_is_all_or_nothing():
    registered, unregistered = [], []

    class Sim(MultiRobotSimulationCore):
        def register_manager(self, manager):
            registered.append(manager)
            super().register_manager(manager)

        def unregister_manager(self, manager):
            unregistered.append(manager)
            return super().unregister_manager(manager)

    with Sim(headless_params()) as sim:
        keep = SimObject.from_mesh(BOX, BOX, sim_core=sim, name="keep")
        entries = [
            robot(name="a"),
            robot(grid={"count": 3, "spacing": [1, 1]}),
            robot(name="bad", controller={"type": "warp"}),
        ]
        with pytest.raises(ValueError, match=r"layout\.yaml: entities\[2\].*'warp'"):
            sim.spawn_robots_from_config(entries, source="layout.yaml")
        assert sim.sim_objects == [keep]
        assert len(registered) == 1 and unregistered == registered
        spawned = sim.spawn_robots_from_config(entries[:2])
        assert [o.name for o in spawned] == ["a", None, None, None]


def test_spawn_robots_from_config_manager_must_be_registered(sim):
    with pytest.raises(ValueError, match=r"no manager named 'fleet'.*register_manager"):
        sim.spawn_robots_from_config([robot(manager="fleet")])
    fleet = AgentManager(sim, name="fleet")
    (agent,) = sim.spawn_robots_from_config([robot(manager="fleet")])
    assert fleet.objects == [agent]


# ----- example scenarios ----------------------------------------------------------------------


def test_there_are_example_scenarios():
    assert {path.name for path in EXAMPLES} >= {
        "patrol_grid.yaml",
        "pick_drop.yaml",
        "warehouse.yaml",
    }


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda path: path.name)
def test_example_scenario_runs_headless(build, path):
    config = load_yaml_config(path)
    config["simulation"] = {**config.get("simulation", {}), **HEADLESS}
    sim = build(config, source=str(path), base_dir=path.parent)
    failed = []
    sim.events.on(SimEvents.ACTION_FAILED, lambda agent, action: failed.append(action))
    start = positions(sim.agents)
    for _ in range(400):
        sim.step_once()
    assert failed == []
    standby = sim.get_manager("pickers")  # warehouse.yaml: dispatched by a script, idle here
    idle = set() if standby is None else {a.object_id for a in standby.objects}
    idle |= {a.object_id for a in sim.agents if isinstance(a, Device)}  # move when asked
    if path.name in ("served_fleet.yaml", "served_warehouse.yaml"):  # masters drive them
        idle |= {a.object_id for a in sim.agents}
    assert sim.agents and all(
        not np.allclose(now, then)
        for agent, now, then in zip(sim.agents, positions(sim.agents), start, strict=True)
        if agent.object_id not in idle
    )
    if path.name == "warehouse.yaml":
        names = [o.name for o in sim.sim_objects]
        # A named grid entry names its objects <name>_0, <name>_1, ... (three tote grids, one
        # name each: a scenario's names are unique).
        assert sum(n.startswith("shelf_") for n in names) == 9
        assert sorted(n for n in names if n.startswith("tote_")) == sorted(
            f"tote_A{rack}_{k}" for k in range(4) for rack in (1, 2, 3)
        )
        assert len(names) == len(set(names))
        assert len(standby.objects) == 6
        assert sorted(n for n in names if n.startswith("patrol")) == ["patrol_0", "patrol_1"]
        pallet = next(o for o in sim.sim_objects if o.name == "pallet")
        for _ in range(800):
            sim.step_once()
        assert failed == [] and not pallet.is_attached()
        assert pallet.get_pose().position.tolist() == pytest.approx([-0.5, 18.5, 0.05])
    if path.name == "pick_drop.yaml":
        drops = sorted(
            action["drop_pose"]
            for entity in config["entities"]
            for action in entity.get("actions", [])
            if action["type"] == "drop"
        )
        boxes = [o for o in sim.sim_objects if not o.is_agent]
        assert len(boxes) == len(drops) == 3
        assert all(a.is_action_queue_empty() for a in sim.agents)
        assert not any(box.is_attached() for box in boxes)
        assert np.abs(np.array(sorted(positions(boxes))) - np.array(drops)).max() < 1e-9
    if path.name == "patrol_grid.yaml":
        fleet = sim.get_manager("patrol_fleet")
        assert fleet.objects == sim.agents and len(fleet.objects) == 6
        assert all(isinstance(a.controllers[-1], PatrolController) for a in fleet.objects)


def test_object_managers_have_unique_names(sim):
    crates = SimObjectManager(sim, name="crates")
    assert sim.get_manager("crates") is crates and crates.name == "crates"
    with pytest.raises(ValueError, match="a manager named 'crates' is already registered"):
        AgentManager(sim, name="crates")
    with pytest.raises(ValueError, match=r"SimObjectManager\.name: expected a string"):
        SimObjectManager(sim, name=3)


def test_an_empty_scenario_file_is_refused_naming_it(tmp_path):
    path = tmp_path / "empty.yaml"
    path.write_text("\n")
    with pytest.raises(ValueError, match=r"empty.yaml: the file is empty .*'simulation:'"):
        MultiRobotSimulationCore.from_yaml(path)
