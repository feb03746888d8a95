"""SimObjectManager, AgentManager and GridSpawnParams: placement, sync, bulk control."""

from __future__ import annotations

import logging
import math
from contextlib import contextmanager

import numpy as np
import pybullet as p
import pytest

from fleet_async import (
    Agent,
    AgentManager,
    AgentSpawnParams,
    DifferentialController,
    GridSpawnParams,
    MoveAction,
    MultiRobotSimulationCore,
    OmniController,
    PatrolController,
    Pose,
    ShapeParams,
    SimObject,
    SimObjectManager,
    SimObjectSpawnParams,
    WaitAction,
    register_entity_class,
)
from fleet_async.core.managers import sim_object_manager as managers
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def agent_params(name=None, controller="omni", **kw):
    return AgentSpawnParams(
        visual_shape=BOX, collision_shape=BOX, name=name, controller=controller, **kw
    )


def box_params(name=None, **kw):
    return SimObjectSpawnParams(visual_shape=BOX, collision_shape=BOX, name=name, **kw)


def positions(objects):
    return [obj.get_pose().position.tolist() for obj in objects]


def run_until_idle(sim, manager, max_steps=500):
    """Step until no agent moves and every action queue is empty; return the steps taken."""
    for step in range(1, max_steps + 1):
        sim.step_once()
        idle = all(a.is_action_queue_empty() for a in manager.objects)
        if manager.get_moving_count() == 0 and idle:
            return step
    raise AssertionError("agents did not stop")


def consistent(manager):
    return [o.body_id for o in manager.objects] == manager.body_ids and [
        o.object_id for o in manager.objects
    ] == manager.object_ids


@pytest.fixture
def seeded_sim():
    """Factory of extra headless simulations with a given seed, closed afterwards."""
    opened = []

    def make(seed):
        core = MultiRobotSimulationCore(headless_params(seed=seed))
        opened.append(core)
        return core

    yield make
    for core in opened:
        core.close()


# ----- GridSpawnParams ----------------------------------------------------------------------


def test_grid_cells_are_offset_plus_index_times_spacing_x_fastest():
    grid = GridSpawnParams(0, 2, 0, 1, spacing=[2.0, 3.0], offset=[1.0, -1.0, 0.5])
    assert grid.total_cells == 6
    assert grid.spacing == [2.0, 3.0, 0.0]
    assert grid.cell_positions().tolist() == [
        [1.0, -1.0, 0.5],
        [3.0, -1.0, 0.5],
        [5.0, -1.0, 0.5],
        [1.0, 2.0, 0.5],
        [3.0, 2.0, 0.5],
        [5.0, 2.0, 0.5],
    ]


def test_grid_ranges_are_indices_not_counts_and_z_layers_come_last():
    grid = GridSpawnParams(1, 2, 0, 0, spacing=[1.0, 1.0, 2.0], offset=[0, 0, 0], z_min=0, z_max=1)
    assert grid.total_cells == 4
    assert grid.cell_positions().tolist() == [
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [1.0, 0.0, 2.0],
        [2.0, 0.0, 2.0],
    ]


@pytest.mark.parametrize(
    ("count", "columns", "x_max", "y_max"),
    [(1, None, 0, 0), (4, None, 1, 1), (5, None, 2, 1), (50, 10, 9, 4), (3, 5, 4, 0)],
)
def test_from_count_computes_just_enough_rows(count, columns, x_max, y_max):
    grid = GridSpawnParams.from_count(count, columns=columns)
    assert (grid.x_min, grid.x_max, grid.y_min, grid.y_max) == (0, x_max, 0, y_max)
    assert (grid.z_min, grid.z_max) == (0, 0)
    assert grid.spacing == [1.0, 1.0, 0.0] and grid.offset == [0.0, 0.0, 0.0]


def test_from_dict_accepts_both_formats():
    explicit = GridSpawnParams.from_dict(
        {"x_min": 0, "x_max": 9, "y_min": 0, "y_max": 4, "spacing": [3, 3, 0], "offset": [0, 0, 1]}
    )
    assert (explicit.x_max, explicit.y_max, explicit.total_cells) == (9, 4, 50)
    counted = GridSpawnParams.from_dict(
        {"count": 50, "spacing": [3.0, 3.0], "offset": [0, 0, 0.05], "columns": 10}
    )
    assert counted == GridSpawnParams(0, 9, 0, 4, [3.0, 3.0, 0.0], [0.0, 0.0, 0.05])


@pytest.mark.parametrize(
    ("config", "match"),
    [
        (
            {"x_min": 0, "x_max": 1, "y_min": 0, "y_max": 1, "spacing": [1, 1], "ofset": [0, 0]},
            "ofset",
        ),
        ({"count": 4, "spacing": [1, 1], "colums": 2}, "colums"),
        ({"count": 4, "x_max": 3}, "x_max"),
        ({"x_min": 0, "x_max": 1, "y_min": 0, "spacing": [1, 1], "offset": [0, 0]}, "y_max"),
        ({"count": 0}, r"count.*0"),
        ({"count": 4, "columns": 0}, r"columns.*0"),
    ],
)
def test_from_dict_errors_name_the_key(config, match):
    with pytest.raises(ValueError, match=match):
        GridSpawnParams.from_dict(config)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"x_min": 3, "x_max": 2}, r"x_min.*<= x_max.*3"),
        ({"y_min": 1, "y_max": 0}, r"y_min.*1"),
        ({"z_min": 1, "z_max": 0}, r"z_min.*1"),
        ({"x_min": 0.5}, r"x_min.*integer.*0\.5"),
        ({"spacing": [1.0]}, r"spacing.*\[1\.0\]"),
        ({"spacing": [1, 2, 3, 4]}, "spacing"),
        ({"offset": [0, math.nan, 0]}, "offset"),
    ],
)
def test_grid_validation_names_field_and_value(kwargs, match):
    values = {"x_min": 0, "x_max": 1, "y_min": 0, "y_max": 1, "spacing": [1, 1], "offset": [0, 0]}
    values.update(kwargs)
    with pytest.raises(ValueError, match=match):
        GridSpawnParams(**values)


@pytest.mark.parametrize(
    ("spacing", "match"),
    [
        ([0, 1], r"x spacing > 0 .*2 cell.*\[0\.0, 1\.0, 0\.0\]"),
        ([1, -2], r"y spacing > 0 .*\[1\.0, -2\.0, 0\.0\]"),
        ([1, 1, -1], r"z spacing >= 0 .*1 cell"),
    ],
)
def test_grid_refuses_a_zero_or_negative_spacing(spacing, match):
    with pytest.raises(ValueError, match=match):
        GridSpawnParams(0, 1, 0, 1, spacing=spacing, offset=[0, 0])


def test_count_grid_refuses_a_zero_spacing_naming_the_file():
    with pytest.raises(
        ValueError, match=r"^fleet\.yaml: grid: GridSpawnParams\.spacing.*x spacing"
    ):
        GridSpawnParams.from_dict({"count": 4, "spacing": [0, 0]}, source="fleet.yaml")


def test_grid_takes_a_zero_spacing_on_an_axis_of_one_cell():
    assert GridSpawnParams(0, 0, 0, 2, spacing=[0, 1], offset=[0, 0]).spacing == [0.0, 1.0, 0.0]


# ----- grid spawning ------------------------------------------------------------------------


def test_spawn_objects_grid_places_each_object_on_its_cell_keeping_orientation(sim):
    manager = SimObjectManager(sim)
    grid = GridSpawnParams(0, 1, 0, 1, spacing=[2.0, 3.0], offset=[1.0, 0.0, 0.1])
    params = box_params("crate", initial_pose=Pose.from_euler(9.0, 9.0, 9.0, yaw=math.pi / 2))
    objs = manager.spawn_objects_grid(3, grid, params)
    assert positions(objs) == [[1.0, 0.0, 0.1], [3.0, 0.0, 0.1], [1.0, 3.0, 0.1]]
    assert all(o.get_pose().yaw == pytest.approx(math.pi / 2) for o in objs)
    assert manager.objects == objs and manager.get_object_count() == 3
    assert manager.object_ids == [o.object_id for o in objs] and consistent(manager)
    assert params.initial_pose.position.tolist() == [9.0, 9.0, 9.0]  # the caller's params stay
    assert sim.sim_objects == objs


def test_spawn_agents_grid_fills_3d_layers(sim):
    manager = AgentManager(sim)
    grid = GridSpawnParams(0, 1, 0, 0, spacing=[1.0, 1.0, 2.0], offset=[0, 0, 0.1], z_max=1)
    agents = manager.spawn_agents_grid(4, grid, agent_params())
    assert positions(agents) == [[0, 0, 0.1], [1, 0, 0.1], [0, 0, 2.1], [1, 0, 2.1]]
    assert all(isinstance(a, Agent) for a in agents)
    assert sim.agents == agents


def test_count_based_grid_from_config_spawns_rows_of_columns(sim):
    manager = AgentManager(sim)
    grid = GridSpawnParams.from_dict({"count": 5, "spacing": [2, 3], "offset": [0, 0, 0.1]})
    agents = manager.spawn_agents_grid(5, grid, agent_params())
    assert positions(agents) == [[0, 0, 0.1], [2, 0, 0.1], [4, 0, 0.1], [0, 3, 0.1], [2, 3, 0.1]]


def test_too_many_objects_for_the_grid_spawns_nothing(sim):
    manager = SimObjectManager(sim)
    grid = GridSpawnParams(0, 1, 0, 1, [1, 1], [0, 0])
    with pytest.raises(ValueError, match=r"5 objects.*total_cells=4"):
        manager.spawn_objects_grid(5, grid, box_params())
    with pytest.raises(ValueError, match=r"5 objects.*total_cells=4"):
        manager.spawn_grid_counts(grid, [(box_params(), 3), (box_params(), 2)])
    with pytest.raises(ValueError, match=r"5 objects.*total_cells=4"):
        manager.spawn_grid_mixed(5, grid, [(box_params(), 0.5)])
    assert sim.sim_objects == [] and manager.objects == []


def mixed_layout(sim, seed_probs=(0.5, 0.3)):
    manager = SimObjectManager(sim)
    grid = GridSpawnParams(0, 7, 0, 4, spacing=[1, 1], offset=[0, 0, 0])
    spawned = manager.spawn_grid_mixed(
        40, grid, [(box_params("A"), seed_probs[0]), (box_params("B"), seed_probs[1])]
    )
    return [(tuple(o.get_pose().position.tolist()), o.name) for o in spawned]


def test_spawn_grid_mixed_draws_one_number_per_cell_from_the_sim_rng(sim):
    layout = mixed_layout(sim)
    draws = np.random.default_rng(0).random(40)  # what sim.rng (seed 0) yields
    expected = [
        ((float(i % 8), float(i // 8), 0.0), "A" if u < 0.5 else "B")
        for i, u in enumerate(draws)
        if u < 0.8
    ]
    assert layout == expected
    assert 0 < len(layout) < 40  # some cells stay empty


def test_spawn_grid_mixed_is_reproducible_with_the_seed(seeded_sim):
    first, again, other = seeded_sim(7), seeded_sim(7), seeded_sim(8)
    assert mixed_layout(first) == mixed_layout(again)
    assert mixed_layout(first) != mixed_layout(other)


def test_spawn_grid_mixed_probability_one_fills_every_cell(sim):
    manager = SimObjectManager(sim)
    grid = GridSpawnParams(0, 2, 0, 0, [1, 1], [0, 0])
    objs = manager.spawn_grid_mixed(3, grid, [(box_params("A"), 0.0), (box_params("B"), 1.0)])
    assert [o.name for o in objs] == ["B", "B", "B"]


@pytest.mark.parametrize(
    ("probs", "match"),
    [
        ((-0.1, 0.5), r"entry 0.*\[0, 1\].*-0\.1"),
        ((0.5, 1.5), r"entry 1.*1\.5"),
        ((0.6, 0.6), r"sum to <= 1"),
        ((0.5, "x"), r"entry 1"),
    ],
)
def test_spawn_grid_mixed_rejects_bad_probabilities(sim, probs, match):
    manager = SimObjectManager(sim)
    grid = GridSpawnParams(0, 3, 0, 0, [1, 1], [0, 0])
    with pytest.raises(ValueError, match=match):
        manager.spawn_grid_mixed(4, grid, [(box_params(), probs[0]), (box_params(), probs[1])])
    assert sim.sim_objects == []


def test_spawn_grid_counts_spawns_exact_counts_on_distinct_shuffled_cells(seeded_sim):
    def layout(core):
        manager = AgentManager(core)
        grid = GridSpawnParams(0, 4, 0, 3, spacing=[2, 2], offset=[0, 0, 0.1])
        agents = manager.spawn_agent_grid_counts(
            grid, [(agent_params("A"), 6), (agent_params("B"), 4)]
        )
        cells = {tuple(row) for row in grid.cell_positions().tolist()}
        where = [tuple(p) for p in positions(agents)]
        assert [a.name for a in agents].count("A") == 6 and len(agents) == 10
        assert len(set(where)) == 10 and set(where) <= cells
        assert where == sorted(where, key=lambda p: (p[1], p[0]))  # spawned in cell order
        return [(p, a.name) for p, a in zip(where, agents, strict=True)]

    first, again, other = seeded_sim(3), seeded_sim(3), seeded_sim(4)
    assert layout(first) == layout(again)
    assert layout(first) != layout(other)


def test_spawn_grid_counts_rejects_negative_counts(sim):
    grid = GridSpawnParams(0, 3, 0, 0, [1, 1], [0, 0])
    with pytest.raises(ValueError, match=r"count of entry 1.*-1"):
        SimObjectManager(sim).spawn_grid_counts(grid, [(box_params(), 1), (box_params(), -1)])


def test_random_spawning_needs_a_simulation():
    grid = GridSpawnParams(0, 3, 0, 0, [1, 1], [0, 0])
    with pytest.raises(ValueError, match="random generator"):
        SimObjectManager().spawn_grid_counts(grid, [(box_params(), 1)])


# ----- batch and config spawning --------------------------------------------------------------


def test_spawn_objects_batch_runs_inside_batch_spawn(sim, monkeypatch):
    entered = []
    original = sim.batch_spawn

    @contextmanager
    def recording():
        entered.append(len(sim.sim_objects))
        with original():
            yield
        entered.append(len(sim.sim_objects))

    monkeypatch.setattr(sim, "batch_spawn", recording)
    manager = SimObjectManager(sim)
    objs = manager.spawn_objects_batch(
        [box_params(f"b{i}", initial_pose=Pose.from_xyz(i, 0, 0)) for i in range(3)]
    )
    assert entered == [0, 3]
    assert [o.name for o in objs] == ["b0", "b1", "b2"]
    assert positions(objs) == [[0, 0, 0], [1, 0, 0], [2, 0, 0]]


def test_a_failing_bulk_spawn_leaves_nothing_behind(sim):
    manager = AgentManager(sim)
    keep = manager.spawn_objects_batch([agent_params("before")])
    bodies = p.getNumBodies(physicsClientId=sim.client)
    missing = AgentSpawnParams(visual_shape=ShapeParams("mesh", mesh_path="/no/such/mesh.obj"))
    with pytest.raises(FileNotFoundError, match=r"mesh\.obj"):
        manager.spawn_objects_batch([agent_params("ok"), missing, agent_params("never")])
    assert manager.objects == keep and consistent(manager)
    assert sim.agents == keep
    assert p.getNumBodies(physicsClientId=sim.client) == bodies


def test_spawn_from_config_dispatches_on_type(sim):
    manager = SimObjectManager(sim)
    objs = manager.spawn_from_config(
        [
            {"name": "robot", "visual_shape": {"shape_type": "box", "half_extents": [0.2] * 3}},
            {"type": "sim_object", "name": "crate", "pose": [3, 0, 0.1]},
        ]
    )
    assert [type(o) for o in objs] == [Agent, SimObject]
    assert [o.name for o in objs] == ["robot", "crate"]
    assert objs[1].get_pose().position.tolist() == [3.0, 0.0, 0.1]
    assert manager.objects == objs


def test_spawn_from_config_checks_every_type_before_spawning(sim):
    manager = SimObjectManager(sim)
    with pytest.raises(ValueError, match=r"entities\[1\].*'forklift'.*known types.*agent"):
        manager.spawn_from_config([{"name": "ok"}, {"type": "forklift"}])
    assert sim.sim_objects == []


def test_spawn_from_config_names_the_entry_with_a_bad_key(sim):
    with pytest.raises(ValueError, match=r"entities\[0\].*'nmae'"):
        SimObjectManager(sim).spawn_from_config([{"nmae": "typo"}])


def test_agent_manager_refuses_non_agent_entity_types(sim):
    with pytest.raises(ValueError, match=r"'sim_object'.*AgentManager"):
        AgentManager(sim).spawn_from_config([{"type": "sim_object"}])
    assert sim.sim_objects == []


class Forklift(Agent):
    """A custom entity type for the registry tests."""


def test_register_entity_class_adds_a_type(sim, monkeypatch):
    monkeypatch.setattr(managers, "ENTITY_REGISTRY", dict(managers.ENTITY_REGISTRY))
    register_entity_class("forklift", Forklift)
    register_entity_class("agent_by_path", "fleet_async.core.agents.agent.Agent")
    objs = AgentManager(sim).spawn_from_config([{"type": "forklift"}, {"type": "agent_by_path"}])
    assert [type(o) for o in objs] == [Forklift, Agent]
    with pytest.raises(TypeError, match="not a SimObject subclass"):
        register_entity_class("bad", dict)


def test_spawn_from_yaml_reads_the_key(sim, tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(
        "entities:\n"
        "  - name: r0\n    pose: [1, 2, 0.1]\n"
        "  - type: sim_object\n    name: box\n"
        "robots:\n  - name: r1\n"
    )
    manager = SimObjectManager(sim)
    assert [o.name for o in manager.spawn_from_yaml(path)] == ["r0", "box"]
    assert [o.name for o in manager.spawn_from_yaml(str(path), key="robots")] == ["r1"]
    assert manager.spawn_from_yaml(path, key="nothing_here") == []
    assert manager.get_pose(0).position.tolist() == [1.0, 2.0, 0.1]


def test_spawn_from_yaml_errors_name_the_file(sim, tmp_path):
    with pytest.raises(FileNotFoundError):
        SimObjectManager(sim).spawn_from_yaml(tmp_path / "missing.yaml")
    path = tmp_path / "bad.yaml"
    path.write_text("entities:\n  - type: spaceship\n")
    with pytest.raises(ValueError, match=r"bad\.yaml: entities\[0\].*spaceship"):
        SimObjectManager(sim).spawn_from_yaml(path)


# ----- bookkeeping and poses ----------------------------------------------------------------


def test_pose_helpers(sim):
    manager = SimObjectManager(sim)
    objs = manager.spawn_objects_grid(
        3, GridSpawnParams(0, 2, 0, 0, [1, 1], [0, 0, 1]), box_params()
    )
    assert manager.get_pose(1).position.tolist() == [1.0, 0.0, 1.0]
    assert [p.position.tolist() for p in manager.get_all_poses()] == positions(objs)
    assert {k: v.x for k, v in manager.get_poses_dict().items()} == {
        objs[0].object_id: 0.0,
        objs[1].object_id: 1.0,
        objs[2].object_id: 2.0,
    }
    manager.set_pose_all(lambda o: Pose.from_xyz(o.get_pose().x + 10, 0.0, 0.0))
    assert positions(objs) == [[10, 0, 0], [11, 0, 0], [12, 0, 0]]
    with pytest.raises(IndexError, match="index 3 out of range for 3"):
        manager.get_pose(3)


def test_sim_remove_object_removes_it_from_the_manager(sim):
    manager = AgentManager(sim)
    agents = manager.spawn_agents_grid(
        3, GridSpawnParams(0, 2, 0, 0, [1, 1], [0, 0]), agent_params()
    )
    sim.remove_object(agents[1])
    assert manager.objects == [agents[0], agents[2]]
    assert manager.body_ids == [agents[0].body_id, agents[2].body_id]
    assert manager.object_ids == [agents[0].object_id, agents[2].object_id]
    assert manager.remove_object(agents[1]) is False
    assert manager.remove_object(agents[0]) is True and manager.objects == [agents[2]]
    assert sim.agents == [agents[0], agents[2]]  # the manager alone does not touch the sim


def test_sim_reset_clears_the_manager_and_it_keeps_working(sim):
    manager = AgentManager(sim, name="fleet")
    grid = GridSpawnParams(0, 1, 0, 0, [1, 1], [0, 0])
    manager.spawn_agents_grid(2, grid, agent_params())
    sim.reset()
    assert manager.objects == [] and manager.body_ids == [] and manager.object_ids == []
    assert sim.get_manager("fleet") is manager
    again = manager.spawn_agents_grid(2, grid, agent_params())
    assert manager.objects == again and consistent(manager)


def test_add_object_skips_objects_outside_a_simulation(sim, caplog):
    manager = SimObjectManager(sim)
    standalone = SimObject(body_id=-1)
    with caplog.at_level(logging.WARNING, logger="fleet_async.core.managers.sim_object_manager"):
        manager.add_object(standalone)
    assert manager.objects == [] and "not part of a simulation" in caplog.text


def test_manager_without_sim_joins_the_sim_of_the_first_object(sim):
    manager = SimObjectManager()
    crate = SimObject.from_params(box_params(), sim)
    manager.add_object(crate)
    manager.add_object(crate)  # a second add is ignored
    assert manager.sim_core is sim and manager.objects == [crate]
    sim.remove_object(crate)
    assert manager.objects == []


def test_add_object_refuses_another_simulations_object(sim, seeded_sim):
    other = seeded_sim(0)
    manager = SimObjectManager(sim)
    with pytest.raises(ValueError, match="another simulation"):
        manager.add_object(SimObject.from_params(box_params(), other))


def test_enable_profiling_logs_spawn_time(sim, caplog):
    manager = SimObjectManager(sim, enable_profiling=True)
    with caplog.at_level(logging.INFO, logger="fleet_async.core.managers.sim_object_manager"):
        manager.spawn_objects_batch([box_params()])
    assert "spawn_objects_batch: spawned 1 objects" in caplog.text


# ----- AgentManager: goals, motion, actions ---------------------------------------------------


def line_of_agents(sim, n=3, **kw):
    manager = AgentManager(sim, **kw)
    grid = GridSpawnParams(0, 0, 0, n - 1, spacing=[1, 2], offset=[0, 0, 0.1])
    return manager, manager.spawn_agents_grid(n, grid, agent_params())


def test_goal_helpers_move_the_chosen_agents(sim):
    manager, agents = line_of_agents(sim)
    manager.set_goal_pose(0, Pose.from_xyz(1.0, 0.0, 0.1))
    manager.set_goal_pose_by_body_id(agents[1].body_id, Pose.from_xyz(2.0, 2.0, 0.1))
    manager.set_goal_pose_by_object_id(agents[2].object_id, Pose.from_xyz(-1.0, 4.0, 0.1))
    assert manager.get_moving_count() == 3
    run_until_idle(sim, manager)
    assert positions(agents) == [[1.0, 0.0, 0.1], [2.0, 2.0, 0.1], [-1.0, 4.0, 0.1]]


def test_goal_helpers_report_unknown_agents(sim):
    manager, _ = line_of_agents(sim, n=1)
    goal = Pose.from_xyz(1, 0, 0)
    with pytest.raises(IndexError, match="set_goal_pose: index 5 out of range for 1"):
        manager.set_goal_pose(5, goal)
    with pytest.raises(KeyError, match="body_id 999"):
        manager.set_goal_pose_by_body_id(999, goal)
    with pytest.raises(KeyError, match="object_id 999"):
        manager.set_goal_pose_by_object_id(999, goal)


def test_set_goal_pose_all_and_moving_count(sim):
    manager, agents = line_of_agents(sim)
    manager.set_goal_pose_all(lambda a: Pose.from_xyz(a.get_pose().x + 2.0, a.get_pose().y, 0.1))
    sim.step_once()
    assert manager.get_moving_count() == 3
    steps = run_until_idle(sim, manager)
    # 2 m at 2 m/s, 5 m/s^2, dt 0.1: 0.4 s up (0.4 m), 0.6 s at 2 m/s, 0.4 s down: 14 steps.
    assert steps + 1 == 14
    assert manager.get_moving_count() == 0
    assert positions(agents) == [[2.0, 0.0, 0.1], [2.0, 2.0, 0.1], [2.0, 4.0, 0.1]]


def test_stop_all_stops_every_agent_where_it_is(sim):
    manager, agents = line_of_agents(sim)
    manager.set_goal_pose_all(lambda a: Pose.from_xyz(5.0, a.get_pose().y, 0.1))
    for _ in range(3):
        sim.step_once()
    manager.stop_all()
    stopped = positions(agents)
    assert manager.get_moving_count() == 0 and all(a.goal_pose is None for a in agents)
    for _ in range(5):
        sim.step_once()
    # 0.3 s from rest at 5 m/s^2: 5 * 0.3^2 / 2 = 0.225 m.
    assert positions(agents) == stopped and stopped[0][0] == pytest.approx(0.225)


def test_action_helpers_queue_for_every_agent(sim):
    manager, agents = line_of_agents(sim, n=2)
    manager.add_action_all(lambda a: MoveAction(path=Pose.from_xyz(1.0, a.get_pose().y, 0.1)))
    manager.add_action_sequence_all(
        lambda a: [WaitAction(duration=0.5), MoveAction(path=Pose.from_xyz(1.0, 5.0, 0.1))]
    )
    assert [a.get_action_queue_size() + (a.get_current_action() is not None) for a in agents] == [
        3,
        3,
    ]
    run_until_idle(sim, manager, max_steps=1000)
    assert positions(agents) == [[1.0, 5.0, 0.1], [1.0, 5.0, 0.1]]


class ArmAgent(Agent):
    """Records joint commands (the arm API arrives with the arms issue)."""

    def set_joints_targets(self, targets, max_force=None):
        self.user_data.setdefault("joint_calls", []).append((list(targets), max_force))


def test_set_joints_targets_all_skips_agents_without_joints(sim):
    manager = AgentManager(sim, object_class=ArmAgent)
    arm, cart = manager.spawn_objects_batch(
        [AgentSpawnParams(urdf_path="arm_robot", use_fixed_base=True), agent_params()]
    )
    asked = []
    manager.set_joints_targets_all(lambda a: asked.append(a) or [0.1, 0.2], max_force=100.0)
    assert asked == [arm]
    assert arm.user_data["joint_calls"] == [([0.1, 0.2], 100.0)]
    assert "joint_calls" not in cart.user_data


# ----- callbacks, names, camera -------------------------------------------------------------


def test_register_callback_runs_at_its_frequency_in_sim_time(sim):
    manager, _ = line_of_agents(sim, n=1, update_frequency=5.0)
    calls = {"default": [], "2hz": []}
    manager.register_callback(lambda m, dt: calls["default"].append((m, sim.sim_time, dt)))
    manager.register_callback(lambda m, dt: calls["2hz"].append((sim.sim_time, dt)), frequency=2.0)
    for _ in range(12):
        sim.step_once()
    assert [t for _, t, _ in calls["default"]] == pytest.approx([0.2, 0.4, 0.6, 0.8, 1.0])
    assert all(m is manager for m, _, _ in calls["default"])
    assert [dt for _, _, dt in calls["default"]] == pytest.approx([0.2] * 5)
    assert [t for t, _ in calls["2hz"]] == pytest.approx([0.5, 1.0])
    assert [dt for _, dt in calls["2hz"]] == pytest.approx([0.5, 0.5])


def test_register_callback_waits_for_a_simulation(sim):
    manager = AgentManager(update_frequency=10.0)
    seen = []
    manager.register_callback(lambda m, dt: seen.append(sim.sim_time))
    manager.add_object(Agent.from_params(agent_params(), sim))
    for _ in range(3):
        sim.step_once()
    assert seen == pytest.approx([0.1, 0.2])  # 10 Hz: first at t = 0.1, i.e. the 2nd step


def test_register_callback_rejects_bad_frequency(sim):
    with pytest.raises(ValueError, match=r"frequency.*> 0.*-1"):
        AgentManager(sim).register_callback(lambda m, dt: None, frequency=-1)
    with pytest.raises(ValueError, match="update_frequency"):
        AgentManager(sim, update_frequency=0)


def test_get_manager_finds_the_manager_by_name(sim):
    manager = AgentManager(sim, name="delivery_fleet")
    assert sim.get_manager("delivery_fleet") is manager
    assert sim.get_manager("other") is None
    with pytest.raises(ValueError, match="'delivery_fleet' is already registered"):
        AgentManager(sim, name="delivery_fleet")


def test_setup_camera_frames_the_managed_agents(sim):
    manager, _ = line_of_agents(sim, n=3)
    SimObject.from_params(box_params(initial_pose=Pose.from_xyz(100, 100, 0)), sim)
    distance, yaw, pitch, target = manager.setup_camera({"camera_view_type": "top_down"})
    assert target == pytest.approx([0.0, 2.0, 0.1])
    assert (yaw, pitch) == (0.0, -89.9) and distance > 1.0


# ----- fleet controller and batch mode ------------------------------------------------------


def test_fleet_controller_limits_apply_under_each_agents_own(sim):
    fleet = {"max_linear_vel": 0.5, "max_angular_vel": 1.5}
    manager = AgentManager(sim, fleet_controller=fleet)
    plain, own, named, patrol = manager.spawn_objects_batch(
        [
            agent_params(controller=None),
            agent_params(controller={"type": "omni", "max_linear_vel": 1.0}),
            agent_params(controller="omni"),
            agent_params(controller={"type": "patrol", "waypoints": [[1, 0, 0]]}),
        ]
    )
    assert plain.max_linear_vel.tolist() == [0.5] * 3
    assert own.max_linear_vel.tolist() == [1.0] * 3 and own.max_angular_vel.tolist() == [1.5] * 3
    assert type(named.controller) is OmniController and named.max_linear_vel.tolist() == [0.5] * 3
    assert patrol.max_linear_vel.tolist() == [0.5] * 3
    assert isinstance(patrol.controllers[1], PatrolController)


def test_fleet_controller_applies_to_config_and_grid_spawns_and_limits_motion(sim):
    manager = AgentManager(sim, fleet_controller={"max_linear_vel": 0.5})
    (from_config,) = manager.spawn_from_config([{"name": "c", "controller": "omni"}])
    grid = GridSpawnParams(0, 0, 0, 0, [1, 1], [0, 0, 0.1])
    (from_grid,) = manager.spawn_agents_grid(1, grid, agent_params())
    assert from_config.max_linear_vel.tolist() == [0.5] * 3
    from_grid.set_goal_pose(Pose.from_xyz(2.0, 0.0, 0.1))
    speeds = []
    while True:
        sim.step_once()
        speeds.append(float(np.linalg.norm(from_grid.velocity)))
        if not from_grid.is_moving:
            break
    assert max(speeds) == pytest.approx(0.5)
    assert from_grid.get_pose().position.tolist() == [2.0, 0.0, 0.1]


def test_fleet_controller_rejects_unknown_keys(sim):
    with pytest.raises(ValueError, match="max_speed"):
        AgentManager(sim, fleet_controller={"max_speed": 1.0})
    with pytest.raises(ValueError, match=r"max_linear_vel.*-1"):
        AgentManager(sim, fleet_controller={"max_linear_vel": -1})


def test_enable_batch_switches_controllers_keeping_params(sim):
    manager = AgentManager(sim)
    grid = GridSpawnParams(0, 1, 0, 0, [1, 1], [0, 0, 0.1])
    limits = {"type": "differential", "max_linear_vel": 0.7}
    agents = manager.spawn_agents_grid(2, grid, agent_params(controller=limits))
    assert manager.enable_batch("batch_omni") is OmniController
    assert manager.batch_controller == "batch_omni"
    assert all(type(a.controller) is OmniController for a in agents)
    assert all(a.max_linear_vel.tolist() == [0.7] * 3 for a in agents)
    (late,) = manager.spawn_objects_batch([agent_params(controller="differential")])
    assert type(late.controller) is OmniController
    late.set_goal_pose(Pose.from_xyz(0.0, 3.0, 0.1))  # sideways: only omni can
    run_until_idle(sim, manager)
    assert late.get_pose().position.tolist() == [0.0, 3.0, 0.1]
    manager.disable_batch()
    assert manager.batch_controller is None
    (free,) = manager.spawn_objects_batch([agent_params(controller="differential")])
    assert type(free.controller) is DifferentialController


def test_batch_controller_argument_and_dotted_paths(sim):
    manager = AgentManager(sim, batch_controller="batch_differential")
    (agent,) = manager.spawn_objects_batch([agent_params(controller="omni")])
    assert type(agent.controller) is DifferentialController
    manager.enable_batch("fleet_async.core.motion.controllers.OmniController")
    assert type(agent.controller) is OmniController


@pytest.mark.parametrize(
    "mode",
    [
        "batch_warp",
        "omni",
        "fleet_async.core.motion.controllers.PatrolController",
        "no_such.Module",
    ],
)
def test_enable_batch_rejects_unknown_modes(sim, mode):
    manager = AgentManager(sim)
    with pytest.raises(ValueError, match=rf"{mode}.*batch_differential.*batch_omni"):
        manager.enable_batch(mode)
    assert manager.batch_controller is None
