"""A loaded behaviour tree and how it runs: as one mission, a tick per event it awaits.

BehaviorTree.CPP ticks a tree again and again; a node that is not done answers RUNNING and is
ticked again next time. Here the tree runs as a mission instead: ticking the root calls each
node in turn, and a leaf that has to wait (a move, a door, a lift, a timer) *awaits* its sim
event. While it waits, that leaf, and every node above it, is RUNNING: the mission is parked
until the event arrives, and the step loop runs meanwhile. When the event arrives the leaf
returns SUCCESS or FAILURE and its parent goes on, in the same instant. So the tree is ticked
exactly when something it waits for happens, never on a wall clock, and a run is
deterministic in sim time. Status changes can be observed with :meth:`BehaviorTree.add_listener`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from fleet_async.behavior.ports import Blackboard, NodeStatus

if TYPE_CHECKING:
    from fleet_async.behavior.model import TreeNode
    from fleet_async.core import Agent, MultiRobotSimulationCore

__all__ = ["BehaviorTree", "Listener", "Scope", "tick"]

Listener = Callable[[float, "TreeNode", NodeStatus], None]
"""``listener(sim_time, node, status)``: RUNNING when a node starts, then its result."""


@dataclass
class Scope:
    """What a node runs with: its tree, the blackboard of its (sub)tree, the sim, the agent."""

    tree: BehaviorTree
    blackboard: Blackboard
    sim: MultiRobotSimulationCore
    agent: Agent | None

    def nested(self, blackboard: Blackboard) -> Scope:
        """The same scope with a SubTree's blackboard."""
        return Scope(self.tree, blackboard, self.sim, self.agent)


async def tick(node: TreeNode, scope: Scope) -> NodeStatus:
    """Tick ``node`` until it returns SUCCESS or FAILURE (awaiting whatever it waits for)."""
    tree = scope.tree
    tree.notify(node, NodeStatus.RUNNING)
    status = await node.model.run(node, scope)
    if not isinstance(status, NodeStatus) or status is NodeStatus.RUNNING:
        raise node.error(f"returned {status!r}; a node must end with SUCCESS or FAILURE")
    tree.notify(node, status)
    return status


class BehaviorTree:
    """A tree loaded by :class:`~fleet_async.behavior.factory.BehaviorTreeFactory`, bound to
    a simulation and (usually) an agent. ``await tree.run()`` inside a mission, or
    ``fleet_async.run(sim, tree.run)``.

    Attributes:
        root: The root node of the main tree.
        tree_id: The main tree's ID.
        blackboard: The main tree's blackboard.
        sim: The simulation.
        agent: The agent the fleet nodes act for (None: every fleet node needs ``robot=``).
        status: The last result of :meth:`run` (None before the first).
    """

    def __init__(
        self,
        root: TreeNode,
        tree_id: str,
        sim: MultiRobotSimulationCore,
        agent: Agent | None,
        blackboard: Blackboard,
    ) -> None:
        self.root = root
        self.tree_id = tree_id
        self.sim = sim
        self.agent = agent
        self.blackboard = blackboard
        self.status: NodeStatus | None = None
        self._listeners: list[Listener] = []
        self._rng: Any = None

    @property
    def rng(self) -> Any:
        """The tree's numpy Generator: made from ``sim.mission_rng()`` by the mission that
        first asks (so seeded by the simulation's seed and that mission's place)."""
        if self._rng is None:
            self._rng = self.sim.mission_rng()
        return self._rng

    def add_listener(self, listener: Listener) -> None:
        """Call ``listener(sim_time, node, status)`` on every status change."""
        self._listeners.append(listener)

    def notify(self, node: TreeNode, status: NodeStatus) -> None:
        """Tell the listeners that ``node`` changed to ``status``."""
        for listener in self._listeners:
            listener(self.sim.sim_time, node, status)

    async def run(self) -> NodeStatus:
        """Tick the root until it ends; return SUCCESS or FAILURE (a mission: must be awaited
        inside ``fleet_async.run``)."""
        self.status = await tick(self.root, Scope(self, self.blackboard, self.sim, self.agent))
        return self.status

    async def tick_while_running(self) -> NodeStatus:
        """BehaviorTree.CPP's name for :meth:`run`."""
        return await self.run()

    def __repr__(self) -> str:
        return f"<BehaviorTree {self.tree_id!r} from {self.root.source}>"


def describe(value: Any) -> str:
    """Short text for a value in messages and traces."""
    name = getattr(value, "name", None)
    return str(name) if isinstance(name, str) else repr(value)
