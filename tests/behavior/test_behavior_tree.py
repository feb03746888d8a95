"""The BehaviorTree.CPP v4 subset runner: node semantics in exact sim time, ports and the
blackboard, SubTrees, user nodes, fleet nodes, and errors that name the file, line and node."""

from __future__ import annotations

import math

import pytest

from fleet_async import Agent, DeviceEvents, Door, Elevator, Pose, ShapeParams
from fleet_async.behavior import (
    BehaviorTreeError,
    BehaviorTreeFactory,
    InputPort,
    NodeStatus,
    OutputPort,
)
from fleet_async.core.devices import WorkcellPlugin

BOX = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])


def doc(body: str, *trees: str) -> str:
    extra = "".join(trees)
    head = '<root BTCPP_format="4" main_tree_to_execute="Main">\n<BehaviorTree ID="Main">'
    return f"{head}\n{body}\n</BehaviorTree>{extra}\n</root>"


def bot(sim, name: str = "bot", x: float = 0.0) -> Agent:
    return Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(x, 0, 0.1), sim_core=sim, name=name, controller="omni"
    )


def traced(tree) -> list[tuple[float, str, str]]:
    log: list[tuple[float, str, str]] = []
    tree.add_listener(lambda t, node, status: log.append((round(t, 3), node.label, status.value)))
    return log


async def test_a_sequence_ticks_once_per_awaited_event_in_sim_time(fleet_sim):
    factory = BehaviorTreeFactory()
    heard: list[tuple[float, str]] = []

    @factory.action("Say", ports=[InputPort("text")])
    async def say(ctx, text):
        heard.append((ctx.sim.now, text))

    robot = bot(fleet_sim)
    tree = factory.create_tree_from_text(
        doc(
            '<Sequence><Say text="start"/><Wait seconds="1.5"/>'
            '<Sleep msec="500"/><Say text="{word}"/></Sequence>'
        ),
        agent=robot,
        blackboard={"word": "done"},
    )
    log = traced(tree)
    assert await tree.run() is NodeStatus.SUCCESS
    assert heard == [(0.0, "start"), (pytest.approx(2.0), "done")]
    assert fleet_sim.step_count == 20
    assert log == [
        (0.0, "Sequence", "RUNNING"),
        (0.0, "Say", "RUNNING"),
        (0.0, "Say", "SUCCESS"),
        (0.0, "Wait", "RUNNING"),
        (1.5, "Wait", "SUCCESS"),
        (1.5, "Sleep", "RUNNING"),
        (2.0, "Sleep", "SUCCESS"),
        (2.0, "Say", "RUNNING"),
        (2.0, "Say", "SUCCESS"),
        (2.0, "Sequence", "SUCCESS"),
    ]


async def test_fallback_inverter_force_and_conditions(fleet_sim):
    factory = BehaviorTreeFactory()
    factory.register_condition("Is", lambda ctx, value: value, [InputPort("value", bool)])
    tree = factory.create_tree_from_text(
        doc(
            """<Sequence>
                 <Fallback><Is value="false"/><Inverter><Is value="true"/></Inverter>
                           <Is name="third" value="true"/></Fallback>
                 <ForceSuccess><AlwaysFailure/></ForceSuccess>
                 <Inverter><ForceFailure><AlwaysSuccess/></ForceFailure></Inverter>
               </Sequence>"""
        ),
        sim=fleet_sim,
    )
    log = traced(tree)
    assert await tree.run() is NodeStatus.SUCCESS
    assert ("third", "SUCCESS") in [(label, s) for _, label, s in log]
    assert fleet_sim.step_count == 0  # nothing here takes sim time


async def test_repeat_and_retry_count_cycles_from_the_blackboard(fleet_sim):
    factory = BehaviorTreeFactory()
    calls = []

    @factory.action("Flaky", ports=[InputPort("fail_first", int)])
    async def flaky(ctx, fail_first):
        calls.append(ctx.sim.now)
        await ctx.sim.sleep(0.1)
        return len(calls) > fail_first

    tree = factory.create_tree_from_text(
        doc(
            '<Sequence><Repeat num_cycles="{n}"><Sleep msec="200"/></Repeat>'
            '<RetryUntilSuccessful num_attempts="3"><Flaky fail_first="2"/></RetryUntilSuccessful>'
            "</Sequence>"
        ),
        sim=fleet_sim,
        blackboard={"n": 3},
    )
    assert await tree.run() is NodeStatus.SUCCESS
    assert calls == [pytest.approx(0.6), pytest.approx(0.7), pytest.approx(0.8)]
    assert fleet_sim.now == pytest.approx(0.9)


async def test_an_endless_loop_that_never_waits_is_an_error(fleet_sim):
    tree = BehaviorTreeFactory().create_tree_from_text(
        doc('<Repeat num_cycles="-1">\n  <AlwaysSuccess/>\n</Repeat>'),
        sim=fleet_sim,
        source="spin.xml",
    )
    with pytest.raises(BehaviorTreeError, match=r"spin.xml:3: <Repeat> looped 10000 times without"):
        await tree.run()


async def test_timeout_fails_at_its_deadline_and_stops_the_robot(fleet_sim):
    robot = bot(fleet_sim)
    tree = BehaviorTreeFactory().create_tree_from_text(
        doc('<Timeout msec="500"><MoveTo goal="10;0;0.1"/></Timeout>'), agent=robot
    )
    assert await tree.run() is NodeStatus.FAILURE
    assert fleet_sim.now == pytest.approx(0.5)
    x = robot.get_pose().x
    await fleet_sim.sleep(1.0)
    assert 0 < x < 10 and robot.get_pose().x == x  # the move was cancelled at the deadline


async def test_parallel_ends_when_enough_branches_succeed(fleet_sim):
    tree = BehaviorTreeFactory().create_tree_from_text(
        doc(
            '<Parallel success_count="1"><Sleep msec="300"/><Sleep name="long" msec="900"/>'
            "</Parallel>"
        ),
        sim=fleet_sim,
    )
    log = traced(tree)
    assert await tree.run() is NodeStatus.SUCCESS
    assert fleet_sim.now == pytest.approx(0.3)
    assert ("long", "SUCCESS") not in [(label, s) for _, label, s in log]


async def test_ports_remap_the_blackboard_and_subtrees_scope_it(fleet_sim):
    factory = BehaviorTreeFactory()
    seen = []

    @factory.action("Make", ports=[InputPort("base", float), OutputPort("result")])
    async def make(ctx, base):
        ctx.set_output("result", base * 2)

    @factory.action("Use", ports=[InputPort("value", float)])
    async def use(ctx, value):
        seen.append(value)

    sub = (
        '<BehaviorTree ID="Double"><Sequence><Make base="{x}" result="{y}"/>'
        '<Use value="{y}"/><Use value="{outer}"/></Sequence></BehaviorTree>'
    )
    tree = factory.create_tree_from_text(
        doc(
            '<Sequence><SetBlackboard value="1.5" output_key="start"/>'
            '<SubTree ID="Double" x="{start}" y="{doubled}" _autoremap="true"/>'
            '<Use value="{doubled}"/></Sequence>',
            sub,
        ),
        sim=fleet_sim,
        blackboard={"outer": 7},
    )
    assert await tree.run() is NodeStatus.SUCCESS
    assert seen == [3.0, 7.0, 3.0]
    assert tree.blackboard.as_dict() == {"outer": 7, "start": "1.5", "doubled": 3.0}


async def test_fleet_nodes_fetch_carry_and_pass_a_door(fleet_sim):
    fleet_sim.register_plugin(
        WorkcellPlugin,
        config={
            "processing_time": 0.5,
            "workcells": {
                "disp": {"kind": "dispenser", "position": [0.0, 0.0]},
                "ing": {"kind": "ingestor", "position": [4.0, 0.0]},
            },
        },
    )
    Door.from_dict({"name": "door", "pose": [2.0, 0.0, 0.0], "yaw": math.pi / 2}, fleet_sim)
    robot = bot(fleet_sim)
    tree = BehaviorTreeFactory().create_tree_from_text(
        doc(
            """<Sequence>
                 <Inverter><IsCarrying/></Inverter>
                 <Dispense station="disp" item="{item}"/>
                 <IsCarrying/>
                 <PassDoor door="door" goal="3.6;0;0.1"/>
                 <Ingest station="ing"/>
               </Sequence>"""
        ),
        agent=robot,
    )
    assert await tree.run() is NodeStatus.SUCCESS
    item = tree.blackboard["item"]
    assert item.name == "disp_item0" and item.sim_core is None  # ingested
    assert robot.get_pose().x == pytest.approx(3.6)


def lift_and_log(sim) -> tuple[Elevator, list[tuple[float, str, str, list[str]]]]:
    """A two-floor lift at x = 5 (3 m up, 1.5 m/s) and a log of its trips."""
    lift = Elevator.from_dict(
        {"name": "lift", "pose": [5.0, 0.0, 0.0], "floors": {"L1": 0.0, "L2": 3.0}, "speed": 1.5},
        sim,
    )
    log: list[tuple[float, str, str, list[str]]] = []

    def logger(what: str):
        def handler(floor: str, passengers: tuple[Agent, ...], **_: object) -> None:
            log.append((round(sim.now, 3), what, floor, [p.name for p in passengers]))

        return handler

    sim.events.on(DeviceEvents.ELEVATOR_DEPARTED, logger("departs"))
    sim.events.on(DeviceEvents.ELEVATOR_ARRIVED, logger("arrives"))
    return lift, log


async def test_two_robots_trees_share_the_lift_one_ride_at_a_time(fleet_sim):
    lift, trips = lift_and_log(fleet_sim)
    factory = BehaviorTreeFactory()
    robots = [
        Agent.from_mesh(
            BOX, BOX, Pose.from_xyz(3.0, y, 0.1), sim_core=fleet_sim, name=name, controller="omni"
        )
        for name, y in (("a", 0.5), ("b", -0.5))
    ]
    ended: dict[str, tuple[NodeStatus, float]] = {}

    async def ride(robot: Agent, exit_y: float) -> None:
        tree = factory.create_tree_from_text(
            doc(f'<RideElevator elevator="lift" floor="L2" exit="6.5;{exit_y};3.1"/>'),
            agent=robot,
        )
        ended[robot.name] = (await tree.run(), round(fleet_sim.now, 3))

    async with fleet_sim.task_group() as tg:
        tg.start_soon(ride, robots[0], 0.5)
        tg.start_soon(ride, robots[1], -0.5)
    # a asked first and rides alone; the lift comes back down empty for b, who waited.
    assert trips == [
        (1.5, "departs", "L1", ["a"]),
        (3.4, "arrives", "L2", ["a"]),
        (4.7, "departs", "L2", []),
        (6.6, "arrives", "L1", []),
        (8.2, "departs", "L1", ["b"]),
        (10.1, "arrives", "L2", ["b"]),
    ]
    assert ended == {"a": (NodeStatus.SUCCESS, 4.7), "b": (NodeStatus.SUCCESS, 11.4)}
    assert [r.get_pose().z for r in robots] == [pytest.approx(3.1)] * 2
    assert lift.height == pytest.approx(3.0)


async def test_a_timeout_cancels_a_ride_mid_way_and_says_so(fleet_sim):
    lift, trips = lift_and_log(fleet_sim)
    robot = Agent.from_mesh(
        BOX, BOX, Pose.from_xyz(3.0, 0.5, 0.1), sim_core=fleet_sim, name="a", controller="omni"
    )
    abandoned: list[tuple[float, str, str]] = []
    fleet_sim.events.on(
        DeviceEvents.ELEVATOR_RIDE_ABANDONED,
        lambda robot, floor, **_: abandoned.append((round(fleet_sim.now, 3), robot.name, floor)),
    )
    tree = BehaviorTreeFactory().create_tree_from_text(
        doc('<Timeout msec="2500"><RideElevator elevator="lift" floor="L2"/></Timeout>'),
        agent=robot,
    )
    assert await tree.run() is NodeStatus.FAILURE
    assert fleet_sim.now == pytest.approx(2.5)  # mid-ride: the lift left L1 at 1.5 s
    assert abandoned == [(2.5, "a", "L2")]
    assert 0.1 < robot.get_pose().z < 3.1
    await fleet_sim.sleep(1.0)
    # The lift finishes its trip with the robot still on the platform.
    assert trips == [(1.5, "departs", "L1", ["a"]), (3.4, "arrives", "L2", ["a"])]
    assert robot.get_pose().z == pytest.approx(3.1) and lift.height == pytest.approx(3.0)


async def test_a_failed_action_is_failure_and_a_missing_entry_is_an_error(fleet_sim):
    robot = bot(fleet_sim)
    factory = BehaviorTreeFactory()
    tree = factory.create_tree_from_text(
        doc('<Fallback><Ingest station="{nowhere}"/><AlwaysSuccess/></Fallback>'),
        agent=robot,
        source="t.xml",
    )
    with pytest.raises(
        BehaviorTreeError,
        match=r"t.xml:3: <Ingest> input port 'station' reads blackboard entry 'nowhere', which",
    ):
        await tree.run()
    fleet_sim.register_plugin(
        WorkcellPlugin, config={"workcells": {"ing": {"kind": "ingestor", "position": [0, 0]}}}
    )
    tree = factory.create_tree_from_text(
        doc('<Fallback><Ingest station="ing"/><AlwaysSuccess name="fallback"/></Fallback>'),
        agent=robot,
    )
    log = traced(tree)
    assert await tree.run() is NodeStatus.SUCCESS  # carries nothing: Ingest fails
    assert [s for _, label, s in log if label == "Ingest"] == ["RUNNING", "FAILURE"]


BAD = [
    (
        "<root><BehaviorTree ID='M'><AlwaysSuccess/></BehaviorTree></root>",
        1,
        'expected <root BTCPP_format="4">',
    ),
    (
        doc("<Sequence>\n<MoveTo gaol='1;2;3'/>\n</Sequence>"),
        4,
        "<MoveTo> has no port 'gaol' (did you mean 'goal'?); ports: goal, robot",
    ),
    (
        doc("<Sequence>\n<MoveTow goal='1;2;3'/>\n</Sequence>"),
        4,
        "<MoveTow> unknown node 'MoveTow' (did you mean 'MoveTo'?)",
    ),
    (doc("<Action ID='Frobnicate'/>"), 3, "<Frobnicate> unknown node 'Frobnicate'"),
    (doc("<Sequence>\n<MoveTo/>\n</Sequence>"), 4, "<MoveTo> input port 'goal' is required"),
    (doc("<Wait seconds='soon'/>"), 3, "<Wait> port 'seconds': expected a number, got 'soon'"),
    (
        doc("<Repeat num_cycles='2'><AlwaysSuccess/><AlwaysSuccess/></Repeat>"),
        3,
        "<Repeat> takes exactly one child, has 2",
    ),
    (doc("<Sequence/>"), 3, "<Sequence> needs at least one child, has 0"),
    (
        doc("<ReactiveSequence><AlwaysSuccess/></ReactiveSequence>"),
        3,
        "<ReactiveSequence> is not supported",
    ),
    (doc("<Dispense station='d' item='item'/>"), 3, "output port must name a blackboard entry"),
    (doc("<MoveTo goal='{goal'/>"), 3, "malformed blackboard reference"),
    (doc("<AlwaysSuccess _skipIf='x'/>"), 3, "attribute '_skipIf' is not supported"),
    (
        doc("<Condition ID='MoveTo' goal='1;2;3'/>"),
        3,
        "declared as <Condition> but 'MoveTo' is an action",
    ),
    (doc("<SubTree ID='Main'/>"), 3, "<SubTree> 'Main' includes itself (Main -> Main)"),
    (doc("<SubTree ID='Nope'/>"), 3, "refers to no tree ('Nope')"),
    (doc("<Sequence>\n<AlwaysSuccess>\n</Sequence>"), 5, "malformed XML: mismatched tag"),
]


@pytest.mark.parametrize(("xml", "line", "message"), BAD, ids=[m[:30] for _, _, m in BAD])
def test_load_errors_name_the_file_the_line_and_the_node(sim, tmp_path, xml, line, message):
    path = tmp_path / "tree.xml"
    path.write_text(xml)
    with pytest.raises(BehaviorTreeError) as caught:
        BehaviorTreeFactory().create_tree_from_file(path, sim=sim)
    text = str(caught.value)
    assert text.startswith(f"{path}:{line}: "), text
    assert message in text, text


def test_registering_nodes_checks_names_and_functions():
    factory = BehaviorTreeFactory()

    async def act(ctx):
        return True

    with pytest.raises(ValueError, match="'MoveTo' is already registered"):
        factory.register_action("MoveTo", act)
    with pytest.raises(ValueError, match="'SubTree' is reserved"):
        factory.register_action("SubTree", act)
    with pytest.raises(TypeError, match="must be an async function"):
        factory.register_action("Sync", lambda ctx: True)
    with pytest.raises(TypeError, match="must be a plain function"):
        factory.register_condition("Async", act)


async def test_the_reference_runners_node_names_work_and_random_waits_are_seeded(fleet_sim):
    robot = bot(fleet_sim)
    xml = doc(
        '<Repeat num_cycles="3"><Sequence><NavigateTo goal="{goal}"/>'
        '<WaitRandom min_seconds="1.0" max_seconds="2.0"/></Sequence></Repeat>'
    )
    tree = BehaviorTreeFactory().create_tree_from_text(
        xml, agent=robot, blackboard={"goal": (1.0, 0.0, 0.1)}
    )
    waits: list[float] = []
    tree.add_listener(
        lambda t, node, status: waits.append(t) if node.label == "WaitRandom" else None
    )
    assert await tree.run() is NodeStatus.SUCCESS
    spans = [round(end - start, 1) for start, end in zip(waits[::2], waits[1::2], strict=True)]
    assert len(set(spans)) > 1 and all(1.0 <= s <= 2.0 for s in spans)
    assert spans == [1.1, 1.1, 1.2]  # the same on every run and backend (seed 0)
