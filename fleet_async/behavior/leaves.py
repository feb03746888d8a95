"""Action and Condition nodes made from Python functions (built-in fleet nodes and users').

An action is ``async def fn(ctx, **inputs)``: it may await anything a mission may (an agent
command, a door, a lift, ``ctx.sim.sleep``). It returns True or None for SUCCESS, False for
FAILURE, or a NodeStatus; an awaited action that fails or is cancelled from outside
(``ActionFailedError`` / ``ActionCancelledError``) is FAILURE too. Any other exception stops
the tree, with the node's file and line in a note. A condition is a plain ``def fn(ctx,
**inputs) -> bool`` and takes no sim time.
"""

from __future__ import annotations

import inspect
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

from fleet_async.behavior.model import NodeModel, TreeNode
from fleet_async.behavior.ports import NodeStatus, Port
from fleet_async.core import SimObject
from fleet_async.tasks import ActionCancelledError, ActionFailedError

if TYPE_CHECKING:
    from fleet_async.behavior.ports import Blackboard
    from fleet_async.behavior.tree import Scope
    from fleet_async.core import Agent, MultiRobotSimulationCore

__all__ = ["NodeContext", "leaf_model"]

logger = logging.getLogger(__name__)

T = TypeVar("T", bound=SimObject)


class NodeContext:
    """What a leaf function is given: the sim, the agent, the blackboard, its node."""

    __slots__ = ("_node", "_scope")

    def __init__(self, node: TreeNode, scope: Scope) -> None:
        self._node = node
        self._scope = scope

    @property
    def sim(self) -> MultiRobotSimulationCore:
        """The simulation."""
        return self._scope.sim

    @property
    def agent(self) -> Agent:
        """The agent the tree runs for.

        Raises:
            BehaviorTreeError: if the tree has none.
        """
        if self._scope.agent is None:
            raise self._node.error("needs an agent: create the tree with agent=...")
        return self._scope.agent

    @property
    def blackboard(self) -> Blackboard:
        """The blackboard of the (sub)tree the node is in."""
        return self._scope.blackboard

    @property
    def rng(self) -> Any:
        """The tree's random generator (deterministic: from the simulation's seed)."""
        return self._scope.tree.rng

    @property
    def node(self) -> TreeNode:
        """The node (``label``, ``source``, ``line``)."""
        return self._node

    def set_output(self, port: str, value: Any) -> None:
        """Write output port ``port``."""
        if port not in self._node.model.ports:
            raise self._node.error(f"has no output port {port!r}")
        self._node.output(self._scope, port, value)

    def find(self, value: Any, kind: type[T]) -> T:
        """``value`` if it is a ``kind``, else the sim object of that kind named ``value``.

        Raises:
            BehaviorTreeError: naming the node and the missing name, or the wrong kind.
        """
        what = kind.__name__
        if isinstance(value, str):
            found = next((o for o in self.sim.sim_objects if o.name == value), None)
            if found is None:
                raise self._node.error(f"no {what} named {value!r} in the simulation")
            value = found
        if not isinstance(value, kind):
            raise self._node.error(f"{value!r} is a {type(value).__name__}, not a {what}")
        return value

    def error(self, reason: str) -> Exception:
        """A BehaviorTreeError located at this node (to raise)."""
        return self._node.error(reason)


def _status(node: TreeNode, result: Any) -> NodeStatus:
    if result is None or result is True:
        return NodeStatus.SUCCESS
    if result is False:
        return NodeStatus.FAILURE
    if isinstance(result, NodeStatus) and result is not NodeStatus.RUNNING:
        return result
    raise node.error(f"returned {result!r}; expected True, False, None or SUCCESS / FAILURE")


def leaf_model(
    name: str,
    category: str,
    fn: Callable[..., Any],
    ports: tuple[Port, ...] | list[Port] = (),
    description: str = "",
) -> NodeModel:
    """The NodeModel of an action (async ``fn``) or a condition (plain ``fn``).

    Raises:
        TypeError: for an action that is not ``async def`` or a condition that is.
    """
    is_async = inspect.iscoroutinefunction(fn)
    if category == "action" and not is_async:
        raise TypeError(f"action {name!r}: {fn!r} must be an async function (async def)")
    if category == "condition" and is_async:
        raise TypeError(f"condition {name!r}: {fn!r} must be a plain function (no waiting)")

    async def run(node: TreeNode, scope: Scope) -> NodeStatus:
        ctx = NodeContext(node, scope)
        inputs = node.inputs(scope)
        try:
            result = await fn(ctx, **inputs) if is_async else fn(ctx, **inputs)
        except (ActionFailedError, ActionCancelledError) as exc:
            logger.debug("%r failed: %s", node, exc)
            return NodeStatus.FAILURE
        except Exception as exc:
            if hasattr(exc, "add_note") and not getattr(exc, "source", None):
                exc.add_note(f"in behaviour tree node {node!r}")
            raise
        return _status(node, result)

    doc = description or (inspect.getdoc(fn) or "").split("\n", 1)[0]
    return NodeModel(name, category, {p.name: p for p in ports}, run, 0, 0, doc)
