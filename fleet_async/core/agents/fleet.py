"""The agents' part of the motion phase: action ticks, per-agent controllers, the engine.

One ``FleetMotion`` belongs to each simulation (``sim.fleet``) and runs as a motion system:

1. the action queues' tick (actions that are due start or advance);
2. per-agent controllers (patrol, random walk, user controllers) for agents that have them;
3. the kinematic engine advances every agent on a built-in controller in one numpy pass, and
   wakes the actions of agents that stopped;
4. per-agent plugins (battery) for agents that have them;
5. timed actions (waits) that end with this step complete, at the step's end time.

Agents without high-level controllers or plugins cost nothing in steps 2 and 4.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

from fleet_async.core.actions.action_queue import ActionQueue
from fleet_async.core.motion.kinematics import KinematicEngine
from fleet_async.core.motion.segments import MotionLimits

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.agents.host import FleetHost

__all__ = ["FleetMotion"]


class FleetMotion:
    """Drives every agent of one simulation."""

    def __init__(self, sim: FleetHost) -> None:
        self._sim = sim
        self.engine = KinematicEngine(sim.state, self._on_motion_end)
        self.actions = ActionQueue(sim)
        self._slot_agent: dict[int, Agent] = {}
        self._controlled: dict[int, Agent] = {}
        self._plugged: dict[int, Agent] = {}
        self._limits: dict[tuple[Any, ...], MotionLimits] = {}
        self._dt = sim.params.timestep

    def add_slot(self, agent: Agent, kind: int) -> int:
        """Give ``agent`` an engine slot; return it."""
        params = agent.controller_params
        key = (
            params.max_linear_vel,
            params.max_linear_accel,
            params.max_angular_vel,
            params.max_angular_accel,
        )
        limits = self._limits.get(key)
        if limits is None:  # MotionLimits is frozen: agents with equal limits share one
            limits = self._limits[key] = params.limits()
        slot = self.engine.add(agent.state_row, kind, limits)
        self._slot_agent[slot] = agent
        return slot

    def cap_speed(self, agent: Agent, max_speed: float | None) -> None:
        """Cap ``agent``'s linear speed at ``max_speed`` m/s (None: back to its own limit).

        Applies from the agent's next path segment (set it before ``set_path``), as an order's
        speed limit on an edge does.
        """
        limits = agent.controller_params.limits()
        if max_speed is not None:
            vmax = limits.max_linear_vel
            capped: float | tuple[float, float, float] = (
                min(vmax, max_speed)
                if isinstance(vmax, float)
                else (min(vmax[0], max_speed), min(vmax[1], max_speed), min(vmax[2], max_speed))
            )
            limits = replace(limits, max_linear_vel=capped)
        self.engine.set_limits(agent.motion_slot, limits)

    def set_time_scale(self, scale_of_row: Any) -> None:
        """Hold (0) or slow (< 1) path following, per store row, in the next step (see
        ``KinematicEngine.set_time_scale``); None drives every agent as planned."""
        self.engine.set_time_scale(scale_of_row)

    def path_rows(self) -> Any:
        """Store rows of the agents following a path on a built-in controller (an array)."""
        return self.engine.path_rows()

    def segment_directions(self) -> Any:
        """(store rows, unit xy directions) of the agents driving a path segment now."""
        return self.engine.segment_directions()

    def remove_slot(self, slot: int) -> None:
        """Release an engine slot."""
        self._slot_agent.pop(slot, None)
        self.engine.remove(slot)

    def track(self, agent: Agent) -> None:
        """Re-read whether ``agent`` needs per-agent controller or plugin calls each step."""
        key = agent.object_id
        if agent.has_stepped_controllers():
            self._controlled[key] = agent
        elif key in self._controlled:
            del self._controlled[key]
        if agent.has_plugins():
            self._plugged[key] = agent
        elif key in self._plugged:
            del self._plugged[key]

    def forget(self, agent: Agent) -> None:
        """Drop everything held for ``agent`` (it left the simulation)."""
        self.actions.forget(agent)
        self._controlled.pop(agent.object_id, None)
        self._plugged.pop(agent.object_id, None)

    def reset(self) -> None:
        """Forget every agent (simulation reset)."""
        self.engine = KinematicEngine(self._sim.state, self._on_motion_end)
        self.actions.reset()
        self._slot_agent.clear()
        self._controlled.clear()
        self._plugged.clear()

    def advance(self, dt: float) -> None:
        """The agents' share of one step's motion phase."""
        self._dt = dt
        self.actions.tick(self._sim.sim_time, dt)
        for agent in tuple(self._controlled.values()):
            agent.step_controllers(dt)
        if not self.engine.is_idle():  # an idle fleet's step costs no array work
            self.engine.advance(dt)
        for agent in tuple(self._plugged.values()):
            agent.step_plugins(dt)
        # Last: a wait that ends with this step has covered all of it (a charge charged).
        self.actions.expire(self._sim.sim_time + dt, dt)

    def idle_steps(self, step: int, limit: int) -> int:
        """How many steps from ``step`` on (at most ``limit``) change no agent: nothing moves,
        no per-agent controller or plugin runs, and no action is due (see ActionQueue)."""
        if self._controlled or self._plugged or not self.engine.is_idle():
            return 0
        return self.actions.idle_steps(step, self._sim.params.timestep, limit)

    def skip(self, last_step: int) -> None:
        """Steps up to ``last_step`` were skipped as empty."""
        self.actions.skip(last_step * self._sim.params.timestep)

    def motion_ended(self, agent: Agent, reached: bool) -> None:
        """Record that ``agent`` stopped and wake an action waiting for it.

        Built-in controllers report through the engine; a custom base controller calls this
        (via ``agent.report_motion_end``) itself.
        """
        agent.note_motion_end(reached)
        self.wake_action(agent)

    def wake_action(self, agent: Agent) -> None:
        """Let the action ``agent`` waits on check its condition again (its joints moved)."""
        now = self._sim.sim_time + self._dt if self._sim.in_step else self._sim.sim_time
        self.actions.on_motion_end(agent, now, self._dt)

    def _on_motion_end(self, slot: int, reached: bool) -> None:
        agent = self._slot_agent.get(slot)
        if agent is not None:
            self.motion_ended(agent, reached)
