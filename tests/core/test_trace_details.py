"""What the trace's event log says beyond an action's class: goals, paths, objects, tasks
(what the viewer's timeline names), and scenario files refusing names given twice."""

from __future__ import annotations

import pytest

from fleet_async import (
    Agent,
    AgentSpawnParams,
    DropAction,
    MoveAction,
    MultiRobotSimulationCore,
    Path,
    PickAction,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    WaitAction,
)
from fleet_async.core.view.trace.action_info import MAX_PATH_POINTS, describe_start
from fleet_async.viewer import TraceReader

BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.1])
TOTE = ShapeParams("box", half_extents=[0.15, 0.15, 0.08])


def robot(sim, name="r"):
    params = AgentSpawnParams(
        visual_shape=BOX,
        collision_shape=BOX,
        initial_pose=Pose.from_xyz(0, 0, 0.1),
        name=name,
        controller={"type": "omni", "max_linear_vel": 1.0},
    )
    return Agent.from_params(params, sim)


def test_action_events_name_goal_path_object_and_task(sim, tmp_path):
    bot = robot(sim)
    box = SimObject.from_mesh(TOTE, TOTE, Pose.from_xyz(2, 0, 0.08), sim_core=sim, name="tote")
    # The object by its PyBullet body id, as pybullet_fleet scripts give it.
    bot.add_action(PickAction(target_object_id=box.body_id, approach_offset=0.5))
    bot.add_action(MoveAction(path=Path([Pose.from_xyz(0, 2, 0.1), Pose.from_xyz(1, 3, 0.1)])))
    bot.add_action(DropAction(drop_pose=Pose.from_xyz(1, 4, 0.08), approach_offset=0.5))
    bot.add_action(WaitAction(duration=2.0, action_type="charge"))
    sim.start_trace(tmp_path / "t.fatrace")
    for _ in range(250):
        sim.step_once()
    sim.events.emit(SimEvents.TASK_COMPLETED, sim=sim, agent=bot, task="order 7: tote to s1")
    sim.step_once()
    sim.stop_trace()
    events = [
        e for e in TraceReader(tmp_path / "t.fatrace").events if e["object_id"] == bot.object_id
    ]
    started = [e["data"] for e in events if e["kind"] == "action_started"]
    ended = [e["data"] for e in events if e["kind"] == "action_ended"]
    assert started == [
        {"action": "PickAction", "object": box.object_id, "goal": [2.0, 0.0]},
        {"action": "MoveAction", "path": [[0.0, 2.0], [1.0, 3.0]], "goal": [1.0, 3.0]},
        {"action": "DropAction", "goal": [1.0, 4.0]},
        {"action": "WaitAction", "duration": 2.0, "label": "charge"},
    ]
    assert [d.get("object") for d in ended] == [box.object_id, None, box.object_id, None]
    assert [d["status"] for d in ended] == ["completed"] * 4
    task = [e for e in events if e["kind"] == "task_completed"]
    assert [e["data"] for e in task] == [{"task": "order 7: tote to s1"}]


def test_long_paths_keep_their_first_waypoints_and_the_goal():
    points = [Pose.from_xyz(float(k), 0.0, 0.0) for k in range(200)]
    data = describe_start(MoveAction(path=Path(points)), [])
    assert len(data["path"]) == MAX_PATH_POINTS
    assert data["path"][-1] == data["goal"] == [199.0, 0.0]
    assert data["path"][: MAX_PATH_POINTS - 1] == [
        [float(k), 0.0] for k in range(MAX_PATH_POINTS - 1)
    ]


def test_a_scenario_refuses_a_name_given_twice(tmp_path):
    path = tmp_path / "twice.yaml"
    box = "visual_shape: {shape_type: box, half_extents: [0.2, 0.2, 0.1]}"
    path.write_text(
        "simulation: {gui: false}\n"
        "entities:\n"
        f"  - {{name: bot, {box}, grid: {{count: 2, spacing: [1, 1], offset: [0, 0, 0.1]}}}}\n"
        f"  - {{name: bot, {box}, grid: {{count: 2, spacing: [1, 1], offset: [0, 5, 0.1]}}}}\n"
    )
    with pytest.raises(
        ValueError, match=r"twice\.yaml: entities: the name 'bot_0' is given to 2 bodies"
    ) as info:
        MultiRobotSimulationCore.from_yaml(path)
    assert "and 1 more shared names" in str(info.value)
    assert "give each entry its own name" in str(info.value)


def test_python_keeps_shared_names_as_given(sim):
    # The seed allows two bodies with one name; the viewer shows them as name#id.
    a, b = robot(sim, "twin"), robot(sim, "twin")
    assert (a.name, b.name) == ("twin", "twin") and a.object_id != b.object_id
