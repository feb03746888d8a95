"""The BehaviorTree.CPP v4 control, decorator and basic leaf nodes this runner supports.

Controls: Sequence, SequenceWithMemory, Fallback, Parallel. Decorators: Inverter,
ForceSuccess, ForceFailure, Repeat, RetryUntilSuccessful, KeepRunningUntilFailure, Delay,
Timeout. Leaves: AlwaysSuccess, AlwaysFailure, SetBlackboard, Sleep. Durations (``msec``,
``delay_msec``) are sim-time milliseconds. The reactive controls (ReactiveSequence,
ReactiveFallback) re-tick conditions while an action runs, which has no meaning when a tick is
an await; they are not supported, and loading a tree that uses them says so.
"""

from __future__ import annotations

from typing import Any

from fleet_async.behavior.model import NodeModel, TreeNode
from fleet_async.behavior.ports import InputPort, NodeStatus, Port
from fleet_async.behavior.tree import Scope, tick

__all__ = ["BUILTIN_MODELS", "UNSUPPORTED", "ZERO_TIME_CYCLES"]

SUCCESS, FAILURE = NodeStatus.SUCCESS, NodeStatus.FAILURE

ZERO_TIME_CYCLES = 10_000
"""An endless loop whose child ends this many times in a row without sim time passing is an
error (it would spin forever at one instant)."""

UNSUPPORTED = {
    "ReactiveSequence": "re-ticks its conditions while an action runs",
    "ReactiveFallback": "re-ticks its conditions while an action runs",
    "IfThenElse": "not implemented",
    "WhileDoElse": "re-ticks its condition while an action runs",
    "Switch2": "not implemented",
    "Switch3": "not implemented",
    "RunOnce": "not implemented",
    "Precondition": "needs the scripting language",
    "Script": "needs the scripting language",
    "ScriptCondition": "needs the scripting language",
}
"""BehaviorTree.CPP nodes this runner knows of but does not run, with why."""


class _Spin:
    """Counts consecutive loop cycles that took no sim time."""

    def __init__(self, node: TreeNode, scope: Scope) -> None:
        self.node, self.scope = node, scope
        self.count, self.step = 0, scope.sim.step_count

    def cycle(self) -> None:
        step = self.scope.sim.step_count
        self.count = self.count + 1 if step == self.step else 0
        self.step = step
        if self.count >= ZERO_TIME_CYCLES:
            raise self.node.error(
                f"looped {self.count} times without sim time passing (at t = "
                f"{self.scope.sim.sim_time:g} s): its child never waits, so it would spin forever"
            )


async def _sequence(node: TreeNode, scope: Scope) -> NodeStatus:
    for child in node.children:
        if await tick(child, scope) is FAILURE:
            return FAILURE
    return SUCCESS


async def _fallback(node: TreeNode, scope: Scope) -> NodeStatus:
    for child in node.children:
        if await tick(child, scope) is SUCCESS:
            return SUCCESS
    return FAILURE


async def _parallel(node: TreeNode, scope: Scope) -> NodeStatus:
    n = len(node.children)
    need_success = _threshold(node, scope, "success_count", n)
    need_failure = _threshold(node, scope, "failure_count", n)
    counts = {SUCCESS: 0, FAILURE: 0}
    decided: list[NodeStatus] = []
    async with scope.sim.task_group() as group:

        async def branch(child: TreeNode) -> None:
            status = await tick(child, scope)
            counts[status] += 1
            if not decided and counts[SUCCESS] >= need_success:
                decided.append(SUCCESS)
            elif not decided and counts[FAILURE] >= need_failure:
                decided.append(FAILURE)
            if decided:
                group.cancel_scope.cancel()  # the other branches stop (their actions too)

        for child in node.children:
            group.start_soon(branch, child, name=f"{child.label}@{child.line}")
    return decided[0] if decided else FAILURE


def _threshold(node: TreeNode, scope: Scope, port: str, n: int) -> int:
    value = int(node.input(scope, port))
    count = n if value < 0 else value
    if count > n or count == 0:
        raise node.error(f"{port}={value} does not fit its {n} children")
    return count


async def _only_child(node: TreeNode, scope: Scope) -> NodeStatus:
    return await tick(node.children[0], scope)


async def _inverter(node: TreeNode, scope: Scope) -> NodeStatus:
    return FAILURE if await _only_child(node, scope) is SUCCESS else SUCCESS


async def _force_success(node: TreeNode, scope: Scope) -> NodeStatus:
    await _only_child(node, scope)
    return SUCCESS


async def _force_failure(node: TreeNode, scope: Scope) -> NodeStatus:
    await _only_child(node, scope)
    return FAILURE


async def _rerun(node: TreeNode, scope: Scope, port: str, until: NodeStatus) -> NodeStatus:
    """Run the child up to ``port`` times (-1: forever) or until it returns ``until``; that
    status then, else the other one (Repeat stops on FAILURE, Retry on SUCCESS)."""
    limit = int(node.input(scope, port))
    spin, runs = _Spin(node, scope), 0
    while limit < 0 or runs < limit:
        if await _only_child(node, scope) is until:
            return until
        runs += 1
        spin.cycle()
    return SUCCESS if until is FAILURE else FAILURE


async def _repeat(node: TreeNode, scope: Scope) -> NodeStatus:
    return await _rerun(node, scope, "num_cycles", FAILURE)


async def _retry(node: TreeNode, scope: Scope) -> NodeStatus:
    return await _rerun(node, scope, "num_attempts", SUCCESS)


async def _keep_running(node: TreeNode, scope: Scope) -> NodeStatus:
    spin = _Spin(node, scope)
    while await _only_child(node, scope) is SUCCESS:
        spin.cycle()
    return FAILURE


async def _delay(node: TreeNode, scope: Scope) -> NodeStatus:
    await scope.sim.sleep(int(node.input(scope, "delay_msec")) / 1000.0)
    return await _only_child(node, scope)


async def _timeout(node: TreeNode, scope: Scope) -> NodeStatus:
    with scope.sim.move_on_after(int(node.input(scope, "msec")) / 1000.0) as deadline:
        return await _only_child(node, scope)
    assert deadline.cancelled_caught
    return FAILURE  # the child was stopped (and its action cancelled) at the deadline


async def _always_success(node: TreeNode, scope: Scope) -> NodeStatus:
    return SUCCESS


async def _always_failure(node: TreeNode, scope: Scope) -> NodeStatus:
    return FAILURE


async def _set_blackboard(node: TreeNode, scope: Scope) -> NodeStatus:
    # As in BehaviorTree.CPP, output_key names the entry: "answer" and "{answer}" alike.
    key = node.keys.get("output_key") or node.literals["output_key"]
    scope.blackboard[key] = node.input(scope, "value")
    return SUCCESS


async def _sleep(node: TreeNode, scope: Scope) -> NodeStatus:
    await scope.sim.sleep(int(node.input(scope, "msec")) / 1000.0)
    return SUCCESS


def _model(
    name: str,
    category: str,
    run: Any,
    ports: tuple[Port, ...] = (),
    children: tuple[int, int | None] = (0, 0),
    description: str = "",
) -> NodeModel:
    return NodeModel(name, category, {p.name: p for p in ports}, run, *children, description)


_ONE = (1, 1)
_MANY = (1, None)

BUILTIN_MODELS: dict[str, NodeModel] = {
    m.name: m
    for m in (
        _model("Sequence", "control", _sequence, (), _MANY, "children in order, until one fails"),
        _model("SequenceWithMemory", "control", _sequence, (), _MANY, "as Sequence here"),
        _model(
            "Fallback", "control", _fallback, (), _MANY, "children in order, until one succeeds"
        ),
        _model(
            "Parallel",
            "control",
            _parallel,
            (InputPort("success_count", int, -1), InputPort("failure_count", int, 1)),
            _MANY,
            "children at once, as missions, until enough succeed or fail",
        ),
        _model("Inverter", "decorator", _inverter, (), _ONE, "SUCCESS <-> FAILURE"),
        _model("ForceSuccess", "decorator", _force_success, (), _ONE, "always SUCCESS"),
        _model("ForceFailure", "decorator", _force_failure, (), _ONE, "always FAILURE"),
        _model(
            "Repeat",
            "decorator",
            _repeat,
            (InputPort("num_cycles", int),),
            _ONE,
            "the child num_cycles times (-1: forever) while it succeeds",
        ),
        _model(
            "RetryUntilSuccessful",
            "decorator",
            _retry,
            (InputPort("num_attempts", int),),
            _ONE,
            "the child up to num_attempts times (-1: forever) until it succeeds",
        ),
        _model(
            "KeepRunningUntilFailure",
            "decorator",
            _keep_running,
            (),
            _ONE,
            "the child again and again until it fails",
        ),
        _model(
            "Delay",
            "decorator",
            _delay,
            (InputPort("delay_msec", int),),
            _ONE,
            "wait delay_msec of sim time, then the child",
        ),
        _model(
            "Timeout",
            "decorator",
            _timeout,
            (InputPort("msec", int),),
            _ONE,
            "FAILURE (and the child stopped) if it runs longer than msec of sim time",
        ),
        _model("AlwaysSuccess", "action", _always_success, (), (0, 0), "SUCCESS"),
        _model("AlwaysFailure", "action", _always_failure, (), (0, 0), "FAILURE"),
        _model(
            "SetBlackboard",
            "action",
            _set_blackboard,
            (InputPort("value", "any"), InputPort("output_key")),
            (0, 0),
            "copy value into the blackboard entry output_key",
        ),
        _model(
            "Sleep",
            "action",
            _sleep,
            (InputPort("msec", int),),
            (0, 0),
            "wait msec of sim time",
        ),
    )
}
"""The built-in nodes, by ID."""
