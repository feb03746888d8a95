"""Per-agent action queues, advanced by events rather than by polling every agent.

Each agent has a FIFO of actions and at most one current action. In a step's action tick the
runner advances only agents that need it: an agent whose action asked to be polled, one whose
timer came due, or one with a new action queued. Actions waiting for motion are woken by the
kinematic engine when the agent stops. Agents are always advanced in ascending object id, so
the order never depends on dict or set iteration.
"""

from __future__ import annotations

import functools
import heapq
import math
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from fleet_async.core.actions.action import Action
from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.types import ActionStatus

if TYPE_CHECKING:
    from fleet_async.core.actions.host import ActingAgent, QueueHost

__all__ = ["ActionQueue"]

_EPS = 1e-9


class ActionQueue:
    """Every agent's action queue in one simulation."""

    def __init__(self, sim: QueueHost) -> None:
        self._sim = sim
        self._queued: dict[int, deque[Action]] = {}
        self._current: dict[int, Action] = {}
        self._agents: dict[int, ActingAgent] = {}
        self._due: set[int] = set()  # agents to advance at the next tick
        self._on_motion: set[int] = set()  # agents whose action waits for motion to end
        self._timers: list[tuple[float, int, int, Action]] = []
        self._hooks: dict[int, Callable[[Action], None]] = {}  # cancel hooks, one per agent
        self._seq = 0
        self.now = 0.0
        """Sim time the queue is acting at: the step's start in the tick, its end after motion."""

    # ----- queries ------------------------------------------------------------------------

    def current(self, agent: ActingAgent) -> Action | None:
        """The action ``agent`` is executing, or None."""
        return self._current.get(agent.object_id)

    def queued(self, agent: ActingAgent) -> int:
        """Number of actions waiting behind the current one."""
        return len(self._queued.get(agent.object_id, ()))

    def waits_on_motion(self, agent: ActingAgent) -> bool:
        """Whether ``agent``'s current action waits for its motion to end."""
        return agent.object_id in self._on_motion

    def is_idle(self, agent: ActingAgent) -> bool:
        """No current action and nothing queued."""
        return agent.object_id not in self._current and not self._queued.get(agent.object_id)

    def idle_steps(self, step: int, dt: float, limit: int) -> int:
        """How many steps from ``step`` on (at most ``limit``) advance no action: nothing is
        due to start or be polled, and no timer runs out (step ``j`` ends at ``j * dt + dt``)."""
        if self._due:
            return 0
        if not self._timers:
            return limit
        when = self._timers[0][0]
        j = max(step, math.ceil((when - _EPS) / dt) - 2)
        while j * dt + dt + _EPS < when:  # first step whose end reaches the timer
            j += 1
        return max(0, min(limit, j - step))

    def skip(self, now: float) -> None:
        """Steps were skipped; the last one would have ticked at sim time ``now``."""
        self.now = now

    # ----- commands -----------------------------------------------------------------------

    def submit(self, agent: ActingAgent, action: Action) -> None:
        """Queue ``action`` for ``agent``; it starts at the next action tick.

        Raises:
            TypeError: if ``action`` is not an Action.
            ValueError: if it is already queued, running or finished (``reset`` it first).
        """
        if not isinstance(action, Action):
            raise TypeError(f"add_action: expected an Action, got {action!r}")
        if action.status is not ActionStatus.NOT_STARTED:
            raise ValueError(
                f"add_action: {type(action).__name__} is {action.status.value}; "
                "reset() it to reuse it"
            )
        if action.in_queue:
            raise ValueError(f"add_action: this {type(action).__name__} is already queued")
        key = agent.object_id
        self._agents[key] = agent
        self._queued.setdefault(key, deque()).append(action)
        action.bind_cancel_hook(self._hook(agent))
        self._due.add(key)

    def clear(self, agent: ActingAgent) -> None:
        """Cancel the current action and drop every queued one (each marked CANCELLED)."""
        for action in list(self._queued.get(agent.object_id, ())):
            action.cancel()
        current = self._current.get(agent.object_id)
        if current is not None:
            current.cancel()

    def forget(self, agent: ActingAgent, reason: str = "its agent left the simulation") -> None:
        """Drop the agent's actions: each ends CANCELLED with ``reason`` (ACTION_FAILED is
        emitted), so nobody waiting on one waits forever."""
        key = agent.object_id
        dropped = [
            *([self._current.pop(key)] if key in self._current else []),
            *self._queued.pop(key, ()),
        ]
        self._agents.pop(key, None)
        self._hooks.pop(key, None)
        self._due.discard(key)
        self._on_motion.discard(key)
        for action in dropped:
            action.bind_cancel_hook(None)
            if not action.is_complete():
                action.status = ActionStatus.CANCELLED
                action.error_message = reason
                action.end_time = self._sim.sim_time
                self._emit(SimEvents.ACTION_FAILED, agent, action)

    def reset(self) -> None:
        """Forget every queue (simulation reset); unfinished actions end CANCELLED."""
        for key in sorted(set(self._queued) | set(self._current)):
            agent = self._agents.get(key)
            if agent is not None:
                self.forget(agent, "the simulation was reset")
        self._queued.clear()
        self._current.clear()
        self._agents.clear()
        self._hooks.clear()
        self._due.clear()
        self._on_motion.clear()
        self._timers.clear()

    # ----- checkpoints ----------------------------------------------------------------------

    def get_state(self) -> dict[str, Any]:
        """Every queue, current action, timer and wake flag (for ``sim.save_state``)."""
        return {
            "queued": {key: list(q) for key, q in self._queued.items() if q},
            "current": dict(self._current),
            "due": sorted(self._due),
            "on_motion": sorted(self._on_motion),
            "timers": list(self._timers),
            "seq": self._seq,
            "now": self.now,
        }

    def set_state(self, state: dict[str, Any], agent_of: Callable[[int], ActingAgent]) -> None:
        """Replace every queue with ``state`` (from :meth:`get_state`); ``agent_of`` maps an
        object id to its agent. Queued and running actions get their cancel hooks again."""
        self._queued = {key: deque(actions) for key, actions in state["queued"].items()}
        self._current = dict(state["current"])
        self._agents = {key: agent_of(key) for key in {*self._queued, *self._current}}
        for key in (*state["due"], *state["on_motion"]):
            self._agents.setdefault(key, agent_of(key))
        for key, agent in self._agents.items():
            for action in (*self._queued.get(key, ()), *filter(None, [self._current.get(key)])):
                action.bind_cancel_hook(self._hook(agent))
        self._due = set(state["due"])
        self._on_motion = set(state["on_motion"])
        self._timers = list(state["timers"])
        heapq.heapify(self._timers)
        self._seq = state["seq"]
        self.now = state["now"]

    # ----- driving ------------------------------------------------------------------------

    def tick(self, now: float, dt: float) -> None:
        """Advance the agents that are due at sim time ``now`` (before motion)."""
        self.now = now
        self._expire_timers(now)
        if not self._due:
            return
        due, self._due = sorted(self._due), set()
        for key in due:
            agent = self._agents.get(key)
            if agent is not None:
                self._advance(agent, now, dt)

    def expire(self, end: float, dt: float) -> None:
        """After motion: finish timed actions that are due by the step's end time ``end``.

        A WaitAction that ends at the instant this step reaches completes now, with that end
        time, so whoever waits on it resumes at the right instant; the next queued action then
        starts in the following step's tick, at the same sim time.
        """
        if not self._timers or self._timers[0][0] > end + _EPS:
            return
        self.now = end
        for key in sorted(self._expire_timers(end)):
            agent = self._agents.get(key)
            action = self._current.get(key)
            if agent is None or action is None:
                continue
            if self._execute(agent, action, dt):
                self._complete(agent, action, end)  # stays due: the next action starts next tick
            else:
                self._due.discard(key)
                self._park(agent, action)

    def _expire_timers(self, now: float) -> set[int]:
        expired: set[int] = set()
        while self._timers and self._timers[0][0] <= now + _EPS:
            _, _, key, action = heapq.heappop(self._timers)
            if self._current.get(key) is action:
                self._due.add(key)
                expired.add(key)
        return expired

    def on_motion_end(self, agent: ActingAgent, now: float, dt: float) -> None:
        """The engine stopped ``agent`` (during motion; ``now`` is the end of the step)."""
        key = agent.object_id
        if key not in self._on_motion:
            return
        self._on_motion.discard(key)
        action = self._current.get(key)
        if action is None:
            return
        if self._execute(agent, action, dt):
            self._complete(agent, action, now)
            self._due.add(key)  # the next action starts at the next tick
        else:
            self._park(agent, action)

    def _advance(self, agent: ActingAgent, now: float, dt: float) -> None:
        key = agent.object_id
        while True:
            action = self._current.get(key)
            if action is None:
                queue = self._queued.get(key)
                if not queue:
                    return
                action = queue.popleft()
                self._current[key] = action
                action.status = ActionStatus.IN_PROGRESS
                action.start_time = now
                self._emit(SimEvents.ACTION_STARTED, agent, action)
            if not self._execute(agent, action, dt):
                self._park(agent, action)
                return
            self._complete(agent, action, now)

    def _execute(self, agent: ActingAgent, action: Action, dt: float) -> bool:
        try:
            return bool(action.execute(agent, dt))
        except Exception as exc:
            action.fail(f"{type(exc).__name__}: {exc}")
            self._complete(agent, action, self._sim.sim_time)
            raise

    def _park(self, agent: ActingAgent, action: Action) -> None:
        kind, when = action.wait_hint()
        key = agent.object_id
        if kind == "motion":
            self._on_motion.add(key)
        elif kind == "time" and when is not None:
            self._seq += 1
            heapq.heappush(self._timers, (when, self._seq, key, action))
        else:
            self._due.add(key)

    def _complete(self, agent: ActingAgent, action: Action, now: float) -> None:
        if action.status is ActionStatus.IN_PROGRESS:
            action.status = ActionStatus.COMPLETED
        action.end_time = now
        action.bind_cancel_hook(None)
        self._current.pop(agent.object_id, None)
        self._on_motion.discard(agent.object_id)
        event = (
            SimEvents.ACTION_COMPLETED
            if action.status is ActionStatus.COMPLETED
            else SimEvents.ACTION_FAILED
        )
        self._emit(event, agent, action)

    def _hook(self, agent: ActingAgent) -> Callable[[Action], None]:
        """The cancel hook of ``agent``'s actions (one per agent: an allocation per queued
        action would outlive the step and feed the garbage collector's older generations)."""
        hook = self._hooks.get(agent.object_id)
        if hook is None or hook.args[0] is not agent:  # type: ignore[attr-defined]
            hook = self._hooks[agent.object_id] = functools.partial(self._cancelled, agent)
        return hook

    def _cancelled(self, agent: ActingAgent, action: Action) -> None:
        key = agent.object_id
        queue = self._queued.get(key)
        if queue is not None and any(a is action for a in queue):
            queue.remove(action)
            action.end_time = self._sim.sim_time
            self._emit(SimEvents.ACTION_FAILED, agent, action)  # whoever waits on it learns
            return
        if self._current.get(key) is not action:
            return
        self._current.pop(key)
        self._on_motion.discard(key)
        agent.stop()
        action.on_cancel(agent)
        action.end_time = self._sim.sim_time
        self._due.add(key)
        self._emit(SimEvents.ACTION_FAILED, agent, action)

    def _emit(self, event: str, agent: ActingAgent, action: Action) -> None:
        if event == SimEvents.ACTION_STARTED:
            self._sim.events.emit(event, agent=agent, action=action)
            if agent.has_event_bus():
                agent.events.emit(event, agent=agent, action=action)
            return
        status = action.status
        self._sim.events.emit(event, agent=agent, action=action, status=status)
        if agent.has_event_bus():
            agent.events.emit(event, agent=agent, action=action, status=status)
