"""BehaviorTreeFactory: the registry of node types, and where trees are created."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from fleet_async.behavior.builtin_nodes import BUILTIN_MODELS
from fleet_async.behavior.fleet_nodes import FLEET_MODELS
from fleet_async.behavior.leaves import leaf_model
from fleet_async.behavior.loader import load_document
from fleet_async.behavior.model import NodeModel
from fleet_async.behavior.ports import Blackboard, Port
from fleet_async.behavior.tree import BehaviorTree
from fleet_async.behavior.xml_source import parse_xml, read_xml_file

if TYPE_CHECKING:
    from fleet_async.core import Agent, MultiRobotSimulationCore

__all__ = ["BehaviorTreeFactory"]

_RESERVED = {"Action", "Condition", "Control", "Decorator", "SubTree", "BehaviorTree", "root"}
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.-]*$")


class BehaviorTreeFactory:
    """Node types by ID, and the trees built from them.

    Args:
        fleet_nodes: Include the fleet's nodes (MoveTo, PassDoor, RideElevator, Dispense, ...)
            besides BehaviorTree.CPP's built-in controls, decorators and basic leaves.

    Example::

        factory = BehaviorTreeFactory()

        @factory.action("Beep", ports=[InputPort("times", int, 1)])
        async def beep(ctx, times):
            await ctx.sim.sleep(0.1 * times)

        tree = factory.create_tree_from_file("deliver.xml", agent=robot, blackboard={...})
        status = fleet_async.run(sim, tree.run)
    """

    def __init__(self, fleet_nodes: bool = True) -> None:
        self._models: dict[str, NodeModel] = dict(BUILTIN_MODELS)
        if fleet_nodes:
            self._models.update(FLEET_MODELS)

    @property
    def registered_nodes(self) -> dict[str, NodeModel]:
        """Every node type by ID (a copy)."""
        return dict(self._models)

    # ----- registering ------------------------------------------------------------------

    def register_action(
        self,
        name: str,
        fn: Callable[..., Any],
        ports: Sequence[Port] = (),
        *,
        description: str = "",
        replace: bool = False,
    ) -> None:
        """Register ``async def fn(ctx, **inputs)`` as action ``name`` with ``ports``.

        Raises:
            ValueError: for a reserved or malformed name, or a name already registered
                (unless ``replace``).
            TypeError: if ``fn`` is not an async function.
        """
        self._add(leaf_model(name, "action", fn, tuple(ports), description), replace)

    def register_condition(
        self,
        name: str,
        fn: Callable[..., bool],
        ports: Sequence[Port] = (),
        *,
        description: str = "",
        replace: bool = False,
    ) -> None:
        """Register ``def fn(ctx, **inputs) -> bool`` as condition ``name`` with ``ports``.

        Raises:
            ValueError: as :meth:`register_action`.
            TypeError: if ``fn`` is an async function.
        """
        self._add(leaf_model(name, "condition", fn, tuple(ports), description), replace)

    def action(self, name: str, ports: Sequence[Port] = ()) -> Callable[[Any], Any]:
        """Decorator form of :meth:`register_action`."""

        def register(fn: Any) -> Any:
            self.register_action(name, fn, ports)
            return fn

        return register

    def condition(self, name: str, ports: Sequence[Port] = ()) -> Callable[[Any], Any]:
        """Decorator form of :meth:`register_condition`."""

        def register(fn: Any) -> Any:
            self.register_condition(name, fn, ports)
            return fn

        return register

    def _add(self, model: NodeModel, replace: bool) -> None:
        name = model.name
        if not isinstance(name, str) or not _NAME.match(name) or name in _RESERVED:
            raise ValueError(f"node name {name!r} is reserved or not a valid XML tag name")
        if name in self._models and not replace:
            raise ValueError(
                f"a node named {name!r} is already registered ({self._models[name].category}); "
                "pass replace=True to replace it"
            )
        for port in model.ports.values():
            if port.name in ("name", "ID") or port.name.startswith("_"):
                raise ValueError(f"node {name!r}: port name {port.name!r} is reserved")
        self._models[name] = model

    # ----- creating trees -----------------------------------------------------------------

    def create_tree_from_text(
        self,
        text: str,
        *,
        sim: MultiRobotSimulationCore | None = None,
        agent: Agent | None = None,
        blackboard: Mapping[str, Any] | None = None,
        tree_id: str | None = None,
        source: str = "<string>",
    ) -> BehaviorTree:
        """Load a tree from XML text; see :meth:`create_tree_from_file`."""
        root, main = load_document(parse_xml(text, source), source, self._models, tree_id)
        if sim is None and agent is not None:
            # An agent names its simulation by the protocol of its floor; it is the whole one.
            sim = cast("MultiRobotSimulationCore | None", agent.sim_core)
        if sim is None:
            raise ValueError(f"{source}: a tree needs a simulation: pass sim= or agent=")
        return BehaviorTree(root, main, sim, agent, Blackboard(blackboard))

    def create_tree_from_file(
        self,
        path: str | Path,
        *,
        sim: MultiRobotSimulationCore | None = None,
        agent: Agent | None = None,
        blackboard: Mapping[str, Any] | None = None,
        tree_id: str | None = None,
    ) -> BehaviorTree:
        """Load the main tree of a BehaviorTree.CPP v4 XML file, bound to ``sim`` / ``agent``.

        Args:
            path: The XML file.
            sim: The simulation (default: the agent's).
            agent: The agent the fleet nodes act for.
            blackboard: Initial blackboard entries.
            tree_id: The tree to run (default: ``main_tree_to_execute`` or the only one).

        Raises:
            FileNotFoundError: if ``path`` does not exist.
            BehaviorTreeError: for malformed XML, unknown nodes or ports, bad literals, ...,
                naming the file, the line and the node.
        """
        text, source = read_xml_file(path)
        return self.create_tree_from_text(
            text, sim=sim, agent=agent, blackboard=blackboard, tree_id=tree_id, source=source
        )
