"""Whether an order can be run at all, before it touches the vehicle (the order's own shape).

What depends on the vehicle's current order (a new order versus an update, stitching) is
decided in ``vehicle.py``; here only the order itself is read. Each problem is a
:class:`~fleet_async.interfaces.commands.Rejection` naming the order and the node, edge or
task at fault.
"""

from __future__ import annotations

import math

from fleet_async.interfaces.commands import Blocking, Edge, Node, Order, Rejection, Task

__all__ = ["NODE_TASKS", "check_order"]

NODE_TASKS = frozenset({"pick", "drop", "start_charging", "stop_charging"})
"""Task kinds a node or an edge of an order may carry."""

_STANDING = frozenset({"pick", "drop"})
"""Tasks the vehicle does standing still: blocking ``none`` (while driving) is refused."""


def _reject(order: Order, message: str, *refs: tuple[str, str]) -> Rejection:
    references = (("order_id", order.order_id), ("order_update", str(order.update)), *refs)
    return Rejection("order", f"order {order.order_id!r}: {message}", references)


def _check_sequences(order: Order) -> Rejection | None:
    nodes, edges = order.nodes, order.edges
    if not nodes:
        return _reject(order, "has no nodes")
    if len(edges) != len(nodes) - 1:
        return _reject(order, f"has {len(nodes)} nodes but {len(edges)} edges (expected one less)")
    for i, node in enumerate(nodes):
        if node.sequence % 2 or node.sequence < 0:
            return _reject(
                order,
                f"node {node.node_id!r} has sequence {node.sequence} (expected an even number)",
                ("node_id", node.node_id),
            )
        if i and node.sequence != nodes[i - 1].sequence + 2:
            return _reject(
                order,
                f"node {node.node_id!r} has sequence {node.sequence}, expected "
                f"{nodes[i - 1].sequence + 2} (nodes and edges alternate)",
                ("node_id", node.node_id),
            )
    for before, edge, after in zip(nodes, edges, nodes[1:], strict=False):
        if edge.sequence != before.sequence + 1:
            return _reject(
                order,
                f"edge {edge.edge_id!r} has sequence {edge.sequence}, expected "
                f"{before.sequence + 1}",
                ("edge_id", edge.edge_id),
            )
        if (edge.start_node_id, edge.end_node_id) != (before.node_id, after.node_id):
            return _reject(
                order,
                f"edge {edge.edge_id!r} joins {edge.start_node_id!r} to {edge.end_node_id!r} "
                f"but sits between nodes {before.node_id!r} and {after.node_id!r}",
                ("edge_id", edge.edge_id),
            )
    return None


def _check_release(order: Order) -> Rejection | None:
    items: list[Node | Edge] = [
        x for pair in zip(order.nodes, order.edges, strict=False) for x in pair
    ]
    items.append(order.nodes[-1])
    if not items[0].released:
        return _reject(order, "its first node is not released")
    horizon = False
    for item in items:
        if horizon and item.released:
            name = item.node_id if isinstance(item, Node) else item.edge_id
            return _reject(
                order,
                f"{name!r} (sequence {item.sequence}) is released after the horizon began",
                ("node_id" if isinstance(item, Node) else "edge_id", name),
            )
        horizon = horizon or not item.released
    for edge, after in zip(order.edges, order.nodes[1:], strict=False):
        if edge.released and not after.released:
            return _reject(
                order,
                f"edge {edge.edge_id!r} is released but its end node {after.node_id!r} is not "
                "(the base must end on a node)",
                ("edge_id", edge.edge_id),
            )
    return None


def _check_task(order: Order, task: Task, where: tuple[str, str]) -> Rejection | None:
    ref = ("task_id", task.task_id)
    if task.kind not in NODE_TASKS:
        return _reject(
            order,
            f"task {task.task_id!r} of kind {task.kind!r} is not supported on a node or an "
            f"edge (supported: {', '.join(sorted(NODE_TASKS))})",
            where,
            ref,
            ("task_kind", task.kind),
        )
    if task.kind in _STANDING and task.blocking is Blocking.NONE:
        return _reject(
            order,
            f"task {task.task_id!r} ({task.kind}) cannot run while driving (blocking none); "
            "use soft or hard",
            where,
            ref,
        )
    return None


def _check_tasks(
    order: Order, tasks: tuple[Task, ...], where: tuple[str, str], seen: set[str]
) -> Rejection | None:
    """The first problem with a node's or an edge's tasks (``seen``: task ids so far)."""
    for task in tasks:
        problem = _check_task(order, task, where)
        if problem is not None:
            return problem
        if task.task_id in seen:
            return _reject(order, f"task id {task.task_id!r} is used twice", where)
        seen.add(task.task_id)
    return None


def _check_node(order: Order, node: Node, seen: set[str]) -> Rejection | None:
    where = ("node_id", node.node_id)
    if not node.has_position:
        return _reject(order, f"node {node.node_id!r} has no position", where)
    values = (node.x, node.y, node.theta, node.deviation_xy, node.deviation_theta)
    if not all(v is None or math.isfinite(v) for v in values):
        return _reject(order, f"node {node.node_id!r} has a value that is not finite", where)
    return _check_tasks(order, node.tasks, where, seen)


def _check_edge(order: Order, edge: Edge, differential: bool, seen: set[str]) -> Rejection | None:
    where = ("edge_id", edge.edge_id)
    if edge.max_speed is not None and not edge.max_speed > 0:
        return _reject(
            order, f"edge {edge.edge_id!r} has max speed {edge.max_speed!r} (expected > 0)", where
        )
    if edge.orientation is not None and differential:
        forward_or_back = min(
            abs(math.remainder(edge.orientation, 2 * math.pi)),
            abs(math.remainder(edge.orientation - math.pi, 2 * math.pi)),
        )
        if edge.orientation_global or forward_or_back > 1e-3:
            return _reject(
                order,
                f"edge {edge.edge_id!r}: a differential vehicle can only drive forward or "
                f"backward along an edge (orientation {edge.orientation!r}, "
                f"{'global' if edge.orientation_global else 'tangential'})",
                where,
            )
    return _check_tasks(order, edge.tasks, where, seen)


def _check_contents(order: Order, differential: bool) -> Rejection | None:
    seen: set[str] = set()
    for node in order.nodes:
        problem = _check_node(order, node, seen)
        if problem is not None:
            return problem
    for edge in order.edges:
        problem = _check_edge(order, edge, differential, seen)
        if problem is not None:
            return problem
    return None


def check_order(order: Order, differential: bool) -> Rejection | None:
    """The first reason ``order`` cannot be run by any vehicle of its kind, or None.

    Args:
        order: The order as received.
        differential: The vehicle drives like a differential robot (no sideways motion).
    """
    return _check_sequences(order) or _check_release(order) or _check_contents(order, differential)
