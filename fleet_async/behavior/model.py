"""Node models (what a registered node is) and tree nodes (one element of a loaded tree)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from fleet_async.behavior.errors import BehaviorTreeError
from fleet_async.behavior.ports import REQUIRED, Port, convert_literal

if TYPE_CHECKING:
    from fleet_async.behavior.tree import Scope

__all__ = ["CATEGORIES", "NodeModel", "TreeNode"]

CATEGORIES = ("action", "condition", "control", "decorator")
"""Node categories, as BehaviorTree.CPP's (SubTree is handled by the loader)."""

RunFn = Callable[["TreeNode", "Scope"], Any]


@dataclass(frozen=True)
class NodeModel:
    """A node type that XML elements can name.

    Attributes:
        name: The ID (``<MoveTo/>`` or ``<Action ID="MoveTo"/>``).
        category: "action", "condition", "control" or "decorator".
        ports: The ports, by name.
        run: ``async run(node, scope) -> NodeStatus``.
        min_children: Fewest children.
        max_children: Most children (None: any number).
        description: One line for documentation.
    """

    name: str
    category: str
    ports: dict[str, Port]
    run: RunFn
    min_children: int = 0
    max_children: int | None = 0
    description: str = ""


@dataclass
class TreeNode:
    """One node of a loaded tree.

    Attributes:
        model: What it is.
        label: Its ``name`` attribute, or its ID.
        source: The XML file.
        line: The element's line.
        literals: Port -> converted literal value.
        keys: Port -> blackboard key it is remapped to.
        children: Child nodes.
        subtree: For a SubTree: the tree's ID, its remapping and whether it autoremaps.
    """

    model: NodeModel
    label: str
    source: str
    line: int
    literals: dict[str, Any] = field(default_factory=dict)
    keys: dict[str, str] = field(default_factory=dict)
    children: list[TreeNode] = field(default_factory=list)
    subtree: tuple[str, dict[str, str], dict[str, str], bool] | None = None

    def error(self, reason: str) -> BehaviorTreeError:
        """A BehaviorTreeError located at this node."""
        return BehaviorTreeError(reason, source=self.source, line=self.line, node=self.model.name)

    def input(self, scope: Scope, name: str) -> Any:
        """The value of input port ``name``: the blackboard entry it is remapped to, its
        literal, or its default.

        Raises:
            BehaviorTreeError: for a missing blackboard entry or a value of the wrong kind.
        """
        port = self.model.ports[name]
        key = self.keys.get(name)
        if key is None:
            if name in self.literals:
                return self.literals[name]
            if port.default is REQUIRED:
                raise self.error(f"input port {name!r} was not given")
            return port.default
        if key not in scope.blackboard:
            raise self.error(
                f"input port {name!r} reads blackboard entry {key!r}, which is not set "
                f"(entries: {sorted(scope.blackboard.as_dict())})"
            )
        try:
            return convert_literal(port.kind, scope.blackboard[key])
        except (TypeError, ValueError) as exc:
            raise self.error(f"port {name!r} (from {{{key}}}): {exc}") from None

    def output(self, scope: Scope, name: str, value: Any) -> None:
        """Write ``value`` to the blackboard entry output port ``name`` is remapped to (or its
        default key; nowhere if it has none)."""
        key = self.keys.get(name, self.model.ports[name].default)
        if key is not None and key is not REQUIRED:
            scope.blackboard[key] = value

    def inputs(self, scope: Scope) -> dict[str, Any]:
        """Every input port's value, by name."""
        return {
            name: self.input(scope, name)
            for name, port in self.model.ports.items()
            if port.direction == "input"
        }

    def __repr__(self) -> str:
        return f"<{self.model.name} {self.label!r} at {self.source}:{self.line}>"
