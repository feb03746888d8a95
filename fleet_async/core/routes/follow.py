"""FollowRouteAction: drive a route graph's edges one after another, each at its speed limit.

``route_to_node(agent, graph, node_id)`` plans a quickest route from the node nearest the
robot to ``node_id`` (``RouteGraph.shortest_path``) and returns the action; missions await it
as ``await robot.go_to_node(node_id)``, behaviour trees run it with the ``GoToNode`` node, and
synchronous code queues it with ``agent.add_action``. The robot first drives to the start
node (when it is not on it), then edge by edge: each leg's speed is capped at the edge's
``max_speed`` and the cap is lifted at the end (or when the action is cancelled). A node with a
heading makes the robot turn to it on arrival. ``current_edge`` says which edge it drives.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from fleet_async.core.actions.action import TrackedAction, WaitHint
from fleet_async.core.geometry.pose import Pose

if TYPE_CHECKING:
    from fleet_async.core.actions.host import ActingAgent
    from fleet_async.core.routes.graph import RouteGraph

__all__ = ["FollowRouteAction", "RouteLeg", "route_to_node"]

_AT_NODE = 1e-6  # m: a robot this close to the start node is on it


@dataclass(frozen=True)
class RouteLeg:
    """One leg of a route: drive to ``x``, ``y`` (turn to ``theta`` if set) at <= ``max_speed``.

    ``edge_id`` is the edge driven, None for the approach to the start node.
    """

    edge_id: str | None
    node_id: str
    x: float
    y: float
    theta: float | None = None
    max_speed: float | None = None


@dataclass(eq=False)
class FollowRouteAction(TrackedAction):
    """Drive ``legs`` one after another (see the module doc).

    Args:
        legs: The legs, in order (at least one).
    """

    legs: list[RouteLeg] = field(default_factory=list)
    _next: int = field(default=0, init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.legs:
            raise ValueError("FollowRouteAction.legs: expected at least one leg, got none")

    @property
    def current_edge(self) -> str | None:
        """The edge being driven (None before the first edge, during the approach and after)."""
        if self.is_complete() or self._next == 0:
            return None
        return self.legs[self._next - 1].edge_id

    @property
    def goal_node(self) -> str:
        """The node the route ends at."""
        return self.legs[-1].node_id

    def step(self, agent: ActingAgent, dt: float) -> bool:
        """Start the next leg whenever the robot has stopped at the end of the last one."""
        if self._next > 0 and agent.is_moving:
            return False
        if self._next > 0 and agent.motion_result is False:
            _cap(agent, None)
            return self.fail("motion stopped before reaching the goal")
        if agent.motion_blocker is not None:
            return self.fail(f"cannot move: {agent.motion_blocker}")
        while self._next < len(self.legs):
            leg = self.legs[self._next]
            self._next += 1
            z = float(agent.get_pose().position[2])
            if leg.theta is None:
                target = Pose.from_xyz(leg.x, leg.y, z)
            else:
                target = Pose.from_euler(leg.x, leg.y, z, 0.0, 0.0, leg.theta)
            _cap(agent, leg.max_speed)
            agent.set_path(
                [target], auto_approach=True, final_orientation_align=leg.theta is not None
            )
            if agent.is_moving:
                return False
        _cap(agent, None)
        return True

    def wait_hint(self) -> WaitHint:
        """Waits for the end of each leg's motion (as MoveAction)."""
        return ("motion", None)

    def on_cancel(self, agent: ActingAgent) -> None:
        """Lift the speed cap of the leg that was being driven."""
        _cap(agent, None)

    def reset(self) -> None:
        """Forget progress."""
        self._reset_status()
        self._next = 0


def _cap(agent: Any, speed: float | None) -> None:
    sim = agent.sim_core
    if sim is not None and agent.motion_slot >= 0:  # only built-in controllers have limits
        sim.fleet.cap_speed(agent, speed)


def route_to_node(agent: Any, graph: RouteGraph, node_id: str) -> FollowRouteAction:
    """A :class:`FollowRouteAction` from the node nearest ``agent`` to ``node_id``.

    Raises:
        KeyError: for an unknown node.
        ValueError: when ``node_id`` cannot be reached from there.
    """
    goal = graph.node(node_id)
    pose = agent.get_pose()
    x, y = float(pose.position[0]), float(pose.position[1])
    start = graph.nearest_node(x, y)
    legs: list[RouteLeg] = []
    if (start.x - x) ** 2 + (start.y - y) ** 2 > _AT_NODE**2 or start.node_id == goal.node_id:
        legs.append(
            RouteLeg(None, start.node_id, start.x, start.y, start.theta if start is goal else None)
        )
    for edge in graph.shortest_path(start.node_id, goal.node_id):
        node = graph.nodes[edge.end]
        theta = node.theta if node is goal else None
        legs.append(RouteLeg(edge.edge_id, node.node_id, node.x, node.y, theta, edge.max_speed))
    return FollowRouteAction(legs=legs)
