"""The fleet's own leaf nodes: agent commands, doors, lifts and workcells as tree actions.

Each acts for the tree's agent, or for ``robot`` (an agent's name, or an agent on the
blackboard) when given. Objects (``door``, ``elevator``, ``station``, ``object``) are sim
object names or blackboard entries holding the objects. Poses are ``x;y;z`` or ``x;y;z;yaw``
literals, or blackboard entries holding a Pose or a list of numbers; a path (``MoveTo`` and
``PassDoor`` goals) is one pose or several separated by ``|``, or a list of Poses.

======================  =================================================================
Node                    Does (and awaits)
======================  =================================================================
MoveTo goal             ``robot.move(goal)`` (a pose or a path); NavigateTo is the same
GoToNode node           ``robot.go_to_node(node)``: the quickest route on the route graph
WaitRandom              ``sim.sleep(uniform(min_seconds, max_seconds))`` (the tree's rng)
Pick object             ``robot.pick(object)``
Drop pose               ``robot.drop(pose)``
Wait seconds            ``robot.wait(seconds)``
OpenDoor / CloseDoor    ``door.open()`` / ``door.close()``
PassDoor door goal      ``door.pass_through(robot, goal)`` (goal: a path through the door)
CallElevator            ``elevator.go_to(floor)``
RideElevator            ``elevator.ride(robot, floor, exit_pose=exit)`` (lift as a Resource)
Dispense station item   ``station.dispense(robot)``; the new item goes to output ``item``
Ingest station          ``station.ingest(robot)``
IsDoorOpen door         condition: the door is fully open
IsCarrying              condition: the robot carries something
======================  =================================================================
"""

from __future__ import annotations

from typing import Any

from fleet_async.behavior.leaves import NodeContext, leaf_model
from fleet_async.behavior.model import NodeModel
from fleet_async.behavior.ports import InputPort, OutputPort, Port
from fleet_async.core import Agent, Door, Elevator, SimObject, Workcell

__all__ = ["FLEET_MODELS"]

_ROBOT = InputPort("robot", "object", None, "the agent (default: the tree's)")


def _robot(ctx: NodeContext, robot: Any) -> Agent:
    return ctx.agent if robot is None else ctx.find(robot, Agent)


async def _move_to(ctx: NodeContext, goal: Any, robot: Any) -> None:
    await _robot(ctx, robot).move(goal)


async def _go_to_node(ctx: NodeContext, node: str, robot: Any) -> None:
    await _robot(ctx, robot).go_to_node(node)


async def _wait_random(ctx: NodeContext, min_seconds: float, max_seconds: float) -> None:
    if max_seconds < min_seconds:
        raise ctx.error(f"max_seconds ({max_seconds:g}) < min_seconds ({min_seconds:g})")
    await ctx.sim.sleep(float(ctx.rng.uniform(min_seconds, max_seconds)))


async def _pick(ctx: NodeContext, object: Any, robot: Any) -> None:  # port name
    await _robot(ctx, robot).pick(ctx.find(object, SimObject))


async def _drop(ctx: NodeContext, pose: Any, robot: Any) -> None:
    await _robot(ctx, robot).drop(pose)


async def _wait(ctx: NodeContext, seconds: float, robot: Any) -> None:
    await _robot(ctx, robot).wait(seconds)


async def _open_door(ctx: NodeContext, door: Any) -> None:
    await ctx.find(door, Door).open()


async def _close_door(ctx: NodeContext, door: Any) -> None:
    await ctx.find(door, Door).close()


async def _pass_door(ctx: NodeContext, door: Any, goal: Any, robot: Any) -> None:
    await ctx.find(door, Door).pass_through(_robot(ctx, robot), goal)


async def _call_elevator(ctx: NodeContext, elevator: Any, floor: str) -> None:
    await ctx.find(elevator, Elevator).go_to(floor)


async def _ride_elevator(
    ctx: NodeContext, elevator: Any, floor: str, exit: Any, robot: Any
) -> None:
    await ctx.find(elevator, Elevator).ride(_robot(ctx, robot), floor, exit_pose=exit)


async def _dispense(ctx: NodeContext, station: Any, robot: Any) -> None:
    done = await ctx.find(station, Workcell).dispense(_robot(ctx, robot))
    ctx.set_output("item", done.item)


async def _ingest(ctx: NodeContext, station: Any, robot: Any) -> None:
    await ctx.find(station, Workcell).ingest(_robot(ctx, robot))


def _is_door_open(ctx: NodeContext, door: Any) -> bool:
    return bool(ctx.find(door, Door).is_open)


def _is_carrying(ctx: NodeContext, robot: Any) -> bool:
    return bool(_robot(ctx, robot).get_attached_objects())


def _action(name: str, fn: Any, *ports: Port, description: str = "") -> NodeModel:
    return leaf_model(name, "action", fn, ports, description)


FLEET_MODELS: dict[str, NodeModel] = {
    m.name: m
    for m in (
        _action("MoveTo", _move_to, InputPort("goal", "path"), _ROBOT, description="drive to goal"),
        _action(
            "NavigateTo",
            _move_to,
            InputPort("goal", "path"),
            _ROBOT,
            description="drive to goal (the reference runner's name for MoveTo)",
        ),
        _action(
            "GoToNode",
            _go_to_node,
            InputPort("node", str),
            _ROBOT,
            description="drive the route graph's quickest route to node",
        ),
        _action(
            "WaitRandom",
            _wait_random,
            InputPort("min_seconds", float),
            InputPort("max_seconds", float),
            description="sleep a random time in the range",
        ),
        _action("Pick", _pick, InputPort("object", "object"), _ROBOT, description="pick object"),
        _action("Drop", _drop, InputPort("pose", "pose"), _ROBOT, description="drop at pose"),
        _action("Wait", _wait, InputPort("seconds", float), _ROBOT, description="stand still"),
        _action("OpenDoor", _open_door, InputPort("door", "object"), description="open a door"),
        _action("CloseDoor", _close_door, InputPort("door", "object"), description="close a door"),
        _action(
            "PassDoor",
            _pass_door,
            InputPort("door", "object"),
            InputPort("goal", "path"),
            _ROBOT,
            description="take the doorway, open, drive through, close behind",
        ),
        _action(
            "CallElevator",
            _call_elevator,
            InputPort("elevator", "object"),
            InputPort("floor", str),
            description="bring the lift to floor",
        ),
        _action(
            "RideElevator",
            _ride_elevator,
            InputPort("elevator", "object"),
            InputPort("floor", str),
            InputPort("exit", "pose", None),
            _ROBOT,
            description="hold the lift, call, board, travel, alight",
        ),
        _action(
            "Dispense",
            _dispense,
            InputPort("station", "object"),
            OutputPort("item"),
            _ROBOT,
            description="get a new item from a dispenser",
        ),
        _action(
            "Ingest", _ingest, InputPort("station", "object"), _ROBOT, description="hand an item in"
        ),
        leaf_model(
            "IsDoorOpen", "condition", _is_door_open, (InputPort("door", "object"),), "door open"
        ),
        leaf_model("IsCarrying", "condition", _is_carrying, (_ROBOT,), "robot carries something"),
    )
}
"""The fleet nodes, by ID."""
