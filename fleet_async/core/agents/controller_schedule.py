"""Which agents' high-level controllers the fleet calls in a step.

A patrol or a random walk acts only when its agent is free (not moving) and its pause is over;
every other step its ``compute`` returns at once. Calling it every step for every robot costs
a Python call per robot per step, and stops idle steps from being skipped. Controllers that
say when they next need a call (``Controller.wake_time``) are therefore *woken*: each step one
numpy pass picks the agents whose wake time has come and whose engine slot is not moving, and
only those are called, in the order the agents joined. A call at a step where the controller
would have done nothing is harmless, so the pass only has to be conservative, never exact.
Controllers that do not say (user controllers, a custom base controller) are called every step,
as is every controller on the per-robot reference path (``FleetMotion.reference_path``).

A controller's wake time is read again after each call, when its agent's chain changes
(``FleetMotion.track``) and when the clock jumps other than by a skip (a restored checkpoint,
``initialize_simulation``). Changing a controller's attributes by hand between steps takes
effect at its next wake; ``agent.set_controller`` re-reads it at once.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.motion.controllers import (
    GoalController,
    KinematicController,
    PatrolController,
    RandomWalkController,
)

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.motion.controllers import Controller
    from fleet_async.core.motion.kinematics import KinematicEngine

__all__ = ["ControllerSchedule"]

_TOLERANCE = 1e-9  # s: the controllers' own "now + 1e-9 < wake" test


def _wake(agent: Agent) -> float | None:
    """The earliest wake time of ``agent``'s high-level controllers; None if one of them
    (or a custom base controller) needs every step."""
    base = agent.controller
    if not (isinstance(base, KinematicController) and base.vectorized):
        return None
    wake = math.inf
    for ctrl in agent.controllers[1:]:
        when = ctrl.wake_time()
        if when is None:
            return None
        wake = min(wake, when)
    return wake


_BATCHED = (PatrolController, RandomWalkController)
_CONTROLLER_METHODS = ("compute", "ready", "next_goal", "send", "wake_time")
_AGENT_METHODS = ("set_path", "set_goal_pose", "is_moving", "get_current_action")


def _lane(agent: Agent, chain: tuple[Controller, ...]) -> GoalController | None:
    """``agent``'s one goal controller, when its goals may be started in a batch: a patrol or
    random walk whose decisions are the built-in ones (they read and change only their own
    state and their agent's pose, so deferring the starts to the end of the pass changes
    nothing they see), on a movable agent whose motion commands and base are built in."""
    from fleet_async.core.agents.agent import Agent  # agent.py sits above this module

    if len(chain) != 1 or agent.use_fixed_base:
        return None
    ctrl, base = chain[0], agent.controller
    if not (
        isinstance(base, KinematicController)
        and type(base).set_path is KinematicController.set_path
        and all(getattr(type(agent), n) is getattr(Agent, n) for n in _AGENT_METHODS)
    ):
        return None
    for cls in _BATCHED:
        if isinstance(ctrl, cls):
            kind = type(ctrl)
            if all(getattr(kind, n) is getattr(cls, n) for n in _CONTROLLER_METHODS):
                return ctrl
    return None


class ControllerSchedule:
    """The controlled agents of one fleet: called every step, or woken."""

    def __init__(self) -> None:
        self._every: dict[int, Agent] = {}
        self._woken: dict[int, Agent] = {}
        self._agents: list[Agent] = []
        self._chains: list[tuple[Controller, ...]] = []
        self._lanes: list[GoalController | None] = []  # an agent's goal controller, batched
        self._pending: list[tuple[int, Pose]] = []  # (agent index, goal) not sent yet
        self._slots = np.zeros(0, dtype=np.int64)
        self._wakes = np.zeros(0)
        self._stale = False
        self._expected = -1  # the step the wake times are current for
        self.reference = False

    def __bool__(self) -> bool:
        return bool(self._every or self._woken)

    @property
    def polls_every_step(self) -> bool:
        """Whether some agent's controllers are called every step."""
        return bool(self._every)

    def track(self, agent: Agent, controlled: bool) -> None:
        """Re-read how ``agent``'s controllers are called (``controlled``: it has any)."""
        key = agent.object_id
        self.forget(agent)
        if not controlled:
            return
        if not self.reference and _wake(agent) is not None:
            self._woken[key] = agent
            self._stale = True
        else:
            self._every[key] = agent

    def forget(self, agent: Agent) -> None:
        """Stop calling ``agent``'s controllers."""
        key = agent.object_id
        self._every.pop(key, None)
        if self._woken.pop(key, None) is not None:
            self._stale = True

    def clear(self) -> None:
        """Forget every agent."""
        self._every.clear()
        self._woken.clear()
        self._stale = True

    def agents(self) -> list[Agent]:
        """Every controlled agent."""
        return [*self._every.values(), *self._woken.values()]

    def skipped(self, next_step: int) -> None:
        """Steps were skipped up to ``next_step`` (nothing was due: the wakes still hold)."""
        if self._expected >= 0:
            self._expected = next_step

    def run(
        self,
        engine: KinematicEngine,
        step: int,
        now: float,
        dt: float,
        current: Callable[[Agent], object] | None = None,
    ) -> None:
        """Call the controllers due at step ``step`` (sim time ``now``); ``current`` gives an
        agent's current action (the fleet's action queue; None: ask the agent)."""
        for agent in tuple(self._every.values()):
            agent.step_controllers(dt)
        if not self._woken:
            return
        if self._stale or step != self._expected:
            self._rebuild()
        self._expected = step + 1
        due = np.flatnonzero(now + _TOLERANCE >= self._wakes)
        if not len(due):
            return
        due = due[~engine.moving_mask(self._slots[due])]
        try:
            self._call(engine, due, now, dt, current)
        finally:  # the goals decided before a failure start, as one by one they would have
            self._send(engine)

    def _call(
        self,
        engine: KinematicEngine,
        due: np.ndarray,
        now: float,
        dt: float,
        current: Callable[[Agent], object] | None,
    ) -> None:
        agents, chains, wakes, lanes = self._agents, self._chains, self._wakes, self._lanes
        slots = self._slots
        masked = True  # no controller has run yet: due's mask says who moves
        for k in due.tolist():
            agent = agents[k]
            lane = lanes[k]
            if lane is not None and not self._stale:
                # GoalController.compute, with the goal sent in one batch (_send); a lane's
                # agent has the built-in get_current_action: the queue's current action
                if (
                    lane.ready()
                    and (masked or not engine.is_moving(int(slots[k])))
                    and (agent.get_current_action() if current is None else current(agent)) is None
                ):
                    goal = lane.next_goal(agent, now)
                    if goal is not None:
                        if isinstance(goal, Pose) and not agent.path_visualize:
                            self._pending.append((k, goal))
                        else:
                            lane.send(agent, goal)
                wake = lane.wake_time()
                wakes[k] = -math.inf if wake is None else wake
                continue
            self._send(engine)  # every goal before any other controller runs
            masked = False  # it may set robots moving
            if self._stale:  # a controller changed a chain: read every chain afresh
                agent.step_controllers(dt)
                wake = _wake(agent)
            else:  # what step_controllers and _wake do for a woken agent's chain
                chain = chains[k]
                for ctrl in chain:
                    ctrl.compute(agent, dt)
                wake = math.inf
                for ctrl in chain:
                    when = ctrl.wake_time()
                    if when is None:
                        wake = None
                        break
                    wake = min(wake, when)
            wakes[k] = -math.inf if wake is None else wake

    def _send(self, engine: KinematicEngine) -> None:
        """Start the pending goals: what ``agent.set_path([goal])`` does for each, in one
        batch (``KinematicEngine.start_goals``)."""
        pending = self._pending
        if not pending:
            return
        agents = [self._agents[k] for k, _ in pending]
        goals = [goal for _, goal in pending]
        pending.clear()
        if not all(agent.motion_slot >= 0 for agent in agents):  # removed meanwhile: none
            keep = [i for i, agent in enumerate(agents) if agent.motion_slot >= 0]
            agents, goals = [agents[i] for i in keep], [goals[i] for i in keep]
        for agent in agents:
            agent.motion_result = None
        engine.start_goals(
            [agent.motion_slot for agent in agents],
            goals,
            [agent.controller_params.default_direction for agent in agents],
        )

    def idle_steps(self, step: int, dt: float, limit: int) -> int:
        """How many steps from ``step`` on (at most ``limit``) call no controller, given that
        no agent moves."""
        if self._every:
            return 0
        if not self._woken:
            return limit
        if self._stale or step != self._expected:
            self._rebuild()
            self._expected = step
        first = float(self._wakes.min())
        if first == math.inf:
            return limit
        if first == -math.inf:
            return 0
        k = max(step, math.ceil((first - _TOLERANCE) / dt) - 1)
        while k * dt + _TOLERANCE < first:  # the controllers' own test decides
            k += 1
        return min(limit, max(0, k - step))

    def _rebuild(self) -> None:
        agents = list(self._woken.values())
        self._agents = agents
        # A woken agent's base is a built-in controller: a step calls its high-level ones.
        self._chains = [tuple(a.controllers[1:]) for a in agents]
        self._lanes = [_lane(a, chain) for a, chain in zip(agents, self._chains, strict=True)]
        self._slots = np.array([a.motion_slot for a in agents], dtype=np.int64)
        wakes = [_wake(a) for a in agents]
        self._wakes = np.array([-math.inf if w is None else w for w in wakes])
        self._stale = False
