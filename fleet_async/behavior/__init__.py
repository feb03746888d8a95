"""Behaviour trees: a BehaviorTree.CPP v4 XML subset, run as missions in sim time.

Load a tree with :class:`BehaviorTreeFactory` (``create_tree_from_file``), bind it to an
agent, and run it as a mission: ``status = fleet_async.run(sim, tree.run)``, or
``await tree.run()`` inside one. Leaves are bound to the fleet's awaitables (MoveTo, Pick,
Drop, Wait, OpenDoor, PassDoor, RideElevator, Dispense, Ingest, ...) and to functions you
register (``factory.register_action`` / ``register_condition``). A tick happens when an event
the tree awaits arrives, never on a wall clock; see docs/behavior-trees.md.
"""

from fleet_async.behavior.errors import BehaviorTreeError
from fleet_async.behavior.factory import BehaviorTreeFactory
from fleet_async.behavior.leaves import NodeContext
from fleet_async.behavior.ports import Blackboard, InputPort, NodeStatus, OutputPort, Port
from fleet_async.behavior.tree import BehaviorTree

__all__ = [
    "BehaviorTree",
    "BehaviorTreeError",
    "BehaviorTreeFactory",
    "Blackboard",
    "InputPort",
    "NodeContext",
    "NodeStatus",
    "OutputPort",
    "Port",
]
