"""Driving a stretch of an order: released edges turned into one path for the robot.

A :class:`Drive` is a run of consecutive released edges the robot can take in one path: it
ends at the base's last node, at a node with tasks or a heading to reach, and before an edge
with tasks or another speed limit or orientation. Each node of the run is reported reached
once the robot has passed it (the path's waypoint index) or stopped at it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from fleet_async.core.base.types import MotionMode
from fleet_async.core.geometry.pose import Pose
from fleet_async.interfaces.commands import Edge, Node

__all__ = ["Drive", "plan_drive"]


def _style(edge: Edge) -> tuple[Any, ...]:
    return (edge.max_speed, edge.orientation, edge.orientation_global)


class Drive:
    """One path through ``nodes`` (the ends of ``edges``), at ``max_speed`` m/s at most.

    Args:
        nodes: The nodes to pass, in order (the last is where the robot stops).
        waypoints: One pose per node.
        max_speed: Speed cap (m/s), or None for the robot's own limit.
        backward: Drive backward (a differential robot told so by the edges' orientation).
        align: Turn to the last waypoint's heading at the end.
    """

    def __init__(
        self,
        nodes: list[Node],
        waypoints: list[Pose],
        max_speed: float | None,
        backward: bool,
        align: bool,
    ) -> None:
        self.nodes = nodes
        self.waypoints = waypoints
        self.max_speed = max_speed
        self.backward = backward
        self.align = align
        self._reported = 0  # nodes already reported reached
        self._offset = 0  # waypoints dropped from the path given to the robot (a resume)

    @property
    def done(self) -> bool:
        """Whether every node of the run was reached."""
        return self._reported == len(self.nodes)

    def start(self, agent: Any, host: Any) -> None:
        """Send the path (from the first node not yet reached)."""
        self._offset = self._reported
        host.fleet.cap_speed(agent, self.max_speed)
        agent.set_path(
            self.waypoints[self._offset :],
            auto_approach=True,
            final_orientation_align=self.align,
            direction="backward" if self.backward else "forward",
        )

    def resume(self, agent: Any, host: Any) -> None:
        """Drive on after a pause."""
        if not self.done:
            self.start(agent, host)

    def reached(self, agent: Any) -> list[Node]:
        """Nodes reached since the last call, in order."""
        if agent.is_moving:
            count = min(self._offset + agent.current_waypoint_index, len(self.nodes))
        elif agent.motion_result is True:
            count = len(self.nodes)
        else:  # stopped short (a pause): nothing more reached
            count = self._reported
        new = self.nodes[self._reported : count]
        self._reported = max(self._reported, count)
        return new


def _heading(a: tuple[float, float], b: tuple[float, float], fallback: float) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    return math.atan2(dy, dx) if dx * dx + dy * dy > 1e-12 else fallback


def plan_drive(edges: Sequence[Edge], nodes: Sequence[Node], agent: Any) -> Drive:
    """The next run of ``edges`` (the first is released and starts where the robot is).

    Args:
        edges: Edges still to drive, the next first.
        nodes: Nodes still to reach, the end of ``edges[0]`` first.
        agent: The robot (its pose starts the path; its motion mode decides orientation).
    """
    omni = agent.motion_mode is not MotionMode.DIFFERENTIAL
    pose = agent.get_pose()
    here, z, yaw = (pose.x, pose.y), pose.z, pose.yaw
    run_nodes: list[Node] = []
    waypoints: list[Pose] = []
    first = edges[0]
    for i, edge in enumerate(edges):
        if not edge.released or (i and (edge.tasks or _style(edge) != _style(first))):
            break
        node = nodes[i]
        assert node.x is not None
        assert node.y is not None
        there = (node.x, node.y)
        travel = _heading(here, there, yaw)
        if node.theta is not None:
            yaw = node.theta
        elif omni and edge.orientation is not None:
            yaw = edge.orientation if edge.orientation_global else travel + edge.orientation
        else:
            yaw = travel
        waypoints.append(Pose.from_yaw(node.x, node.y, z, yaw))
        run_nodes.append(node)
        here = there
        if node.tasks or node.theta is not None or not node.released:
            break
    last = run_nodes[-1]
    align = last.theta is not None or (omni and first.orientation is not None)
    backward = (
        not omni
        and first.orientation is not None
        and abs(math.remainder(first.orientation - math.pi, 2 * math.pi)) < 1e-3
    )
    return Drive(run_nodes, waypoints, first.max_speed, backward, align)
