"""Turning a BehaviorTree.CPP v4 document into tree nodes, checking it on the way.

Everything that can be checked before the tree runs is: the document's shape, node names,
port names, literal values, required ports, children counts, SubTree references and
recursion. Each error is a BehaviorTreeError with the file, the line and the node.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping

from fleet_async.behavior.builtin_nodes import UNSUPPORTED
from fleet_async.behavior.errors import BehaviorTreeError
from fleet_async.behavior.model import NodeModel, TreeNode
from fleet_async.behavior.ports import (
    REQUIRED,
    Blackboard,
    NodeStatus,
    blackboard_key,
    convert_literal,
)
from fleet_async.behavior.tree import Scope, tick
from fleet_async.behavior.xml_source import Element

__all__ = ["load_document"]

_EXPLICIT = {
    "Action": "action",
    "Condition": "condition",
    "Control": "control",
    "Decorator": "decorator",
}


def _did_you_mean(name: str, options: list[str]) -> str:
    close = difflib.get_close_matches(name, options, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _article(word: str) -> str:
    return f"an {word}" if word[0] in "aeiou" else f"a {word}"


async def _run_subtree(node: TreeNode, scope: Scope) -> NodeStatus:
    assert node.subtree is not None
    _, remap, literals, autoremap = node.subtree
    blackboard = Blackboard(literals, parent=scope.blackboard, remap=remap, autoremap=autoremap)
    return await tick(node.children[0], scope.nested(blackboard))


SUBTREE = NodeModel("SubTree", "decorator", {}, _run_subtree, 1, 1, "another tree of the file")


def load_document(
    root: Element, source: str, models: Mapping[str, NodeModel], tree_id: str | None = None
) -> tuple[TreeNode, str]:
    """The root node of the main tree of document ``root`` and the tree's ID.

    Args:
        root: The parsed document.
        source: Its file, for messages.
        models: Registered node models by ID.
        tree_id: Which tree to run (default: ``main_tree_to_execute``, or the only tree).

    Raises:
        BehaviorTreeError: for anything that is not a valid tree of the supported subset.
    """

    def fail(reason: str, element: Element, node: str | None = None) -> BehaviorTreeError:
        return BehaviorTreeError(reason, source=source, line=element.line, node=node)

    if root.tag != "root":
        raise fail(f"the document element must be <root>, got <{root.tag}>", root)
    if root.attrs.get("BTCPP_format") != "4":
        raise fail(
            f'expected <root BTCPP_format="4"> (BehaviorTree.CPP v4), got BTCPP_format='
            f"{root.attrs.get('BTCPP_format')!r}",
            root,
        )
    trees: dict[str, Element] = {}
    for element in root.children:
        if element.tag == "TreeNodesModel":
            continue  # Groot's palette: not needed to run
        if element.tag != "BehaviorTree":
            raise fail(
                f"unexpected <{element.tag}> under <root>; expected <BehaviorTree> or "
                "<TreeNodesModel> (<include> is not supported)",
                element,
            )
        name = element.attrs.get("ID")
        if not name:
            raise fail("<BehaviorTree> needs an ID attribute", element)
        if name in trees:
            raise fail(f"<BehaviorTree ID={name!r}> is defined twice", element)
        if len(element.children) != 1:
            raise fail(
                f"<BehaviorTree ID={name!r}> must hold exactly one root node, has "
                f"{len(element.children)}",
                element,
            )
        trees[name] = element
    if not trees:
        raise fail("the document holds no <BehaviorTree>", root)
    main = tree_id or root.attrs.get("main_tree_to_execute")
    if main is None:
        if len(trees) > 1:
            raise fail(
                f"several trees ({sorted(trees)}) and no main_tree_to_execute: say which to run",
                root,
            )
        main = next(iter(trees))
    if main not in trees:
        raise fail(f"no <BehaviorTree ID={main!r}>; trees: {sorted(trees)}", root)
    builder = _Builder(source, trees, models)
    return builder.build(trees[main].children[0], [main]), main


class _Builder:
    def __init__(
        self, source: str, trees: dict[str, Element], models: Mapping[str, NodeModel]
    ) -> None:
        self.source, self.trees, self.models = source, trees, models

    def fail(self, reason: str, element: Element, node: str | None) -> BehaviorTreeError:
        return BehaviorTreeError(reason, source=self.source, line=element.line, node=node)

    def build(self, element: Element, stack: list[str]) -> TreeNode:
        tag, attrs = element.tag, element.attrs
        declared = _EXPLICIT.get(tag)
        name = tag
        if declared is not None:
            name = attrs.get("ID", "")
            if not name:
                raise self.fail("needs an ID attribute (the node to run)", element, tag)
        if name == "SubTree":
            return self.subtree(element, stack)
        model = self.models.get(name)
        if model is None:
            if name in UNSUPPORTED:
                raise self.fail(f"is not supported: it {UNSUPPORTED[name]}", element, name)
            known = sorted(self.models)
            raise self.fail(
                f"unknown node {name!r}{_did_you_mean(name, known)}; registered nodes: "
                f"{', '.join(known)}",
                element,
                name,
            )
        if declared is not None and model.category != declared:
            raise self.fail(
                f"is declared as <{tag}> but {name!r} is {_article(model.category)} node",
                element,
                name,
            )
        node = TreeNode(model, attrs.get("name", name), self.source, element.line)
        self.ports(node, element, name)
        self.check_children(model, element, name)
        node.children = [self.build(child, stack) for child in element.children]
        return node

    def ports(self, node: TreeNode, element: Element, name: str) -> None:
        model = node.model
        for attr, value in element.attrs.items():
            if attr in ("name", "ID"):
                continue
            if attr.startswith("_"):
                raise self.fail(
                    f"attribute {attr!r} is not supported (no pre/post conditions or scripting)",
                    element,
                    name,
                )
            port = model.ports.get(attr)
            if port is None:
                ports = sorted(model.ports)
                listed = f"ports: {', '.join(ports)}" if ports else "it has no ports"
                raise self.fail(
                    f"has no port {attr!r}{_did_you_mean(attr, ports)}; {listed}", element, name
                )
            try:
                key = blackboard_key(value, attr)
                if port.direction == "output":
                    if key is None:
                        raise ValueError(
                            f"output port must name a blackboard entry ('{{key}}'), got {value!r}"
                        )
                    node.keys[attr] = key
                elif key is not None:
                    node.keys[attr] = key
                else:
                    node.literals[attr] = convert_literal(port.kind, value)
            except (TypeError, ValueError) as exc:
                raise self.fail(f"port {attr!r}: {exc}", element, name) from None
        for port in model.ports.values():
            given = port.name in node.keys or port.name in node.literals
            if port.direction == "input" and port.default is REQUIRED and not given:
                raise self.fail(f"input port {port.name!r} is required", element, name)

    def check_children(self, model: NodeModel, element: Element, name: str) -> None:
        count, low, high = len(element.children), model.min_children, model.max_children
        if low <= count and (high is None or count <= high):
            return
        if high == 0:
            want = "takes no children"
        elif high == 1:
            want = "takes exactly one child"
        else:
            want = "needs at least one child"
        raise self.fail(f"{want}, has {count}", element, name)

    def subtree(self, element: Element, stack: list[str]) -> TreeNode:
        target = element.attrs.get("ID", "")
        if target not in self.trees:
            raise self.fail(
                f"refers to no tree ({target!r}); trees: {sorted(self.trees)}", element, "SubTree"
            )
        if target in stack:
            chain = " -> ".join([*stack, target])
            raise self.fail(f"{target!r} includes itself ({chain})", element, "SubTree")
        if element.children:
            raise self.fail(
                "takes no children (the tree it names is its child)", element, "SubTree"
            )
        remap: dict[str, str] = {}
        literals: dict[str, str] = {}
        autoremap = False
        for attr, value in element.attrs.items():
            if attr in ("ID", "name"):
                continue
            if attr == "_autoremap":
                autoremap = value.strip().lower() in ("true", "1")
                continue
            if attr.startswith("_"):
                raise self.fail(f"attribute {attr!r} is not supported", element, "SubTree")
            try:
                key = blackboard_key(value, attr)
            except ValueError as exc:
                raise self.fail(f"port {attr!r}: {exc}", element, "SubTree") from None
            if key is None:
                literals[attr] = value
            else:
                remap[attr] = key
        node = TreeNode(SUBTREE, element.attrs.get("name", target), self.source, element.line)
        node.subtree = (target, remap, literals, autoremap)
        node.children = [self.build(self.trees[target].children[0], [*stack, target])]
        return node
