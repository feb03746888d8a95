"""The agents' part of the motion phase: action ticks, per-agent controllers, the engine.

One ``FleetMotion`` belongs to each simulation (``sim.fleet``) and runs as a motion system:

1. the action queues' tick (actions that are due start or advance);
2. per-agent controllers (patrol, random walk, user controllers) for agents that have them;
3. the kinematic engine advances every agent on a built-in controller in one numpy pass, and
   wakes the actions of agents that stopped;
4. every battery whose robot moved in the step, in one numpy pass (``agents/batteries.py``;
   a standing robot's battery follows a formula and costs nothing per step), then per-agent
   plugins that need a call every step (those that override ``on_step``);
5. timed actions (waits) that end with this step complete, at the step's end time.

Agents without high-level controllers or stepped plugins cost nothing in steps 2 and 4.
``reference_path = True`` steps every battery through its own ``on_step`` instead of the
numpy pass: the per-robot reference the vectorized path is tested against (same bits).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

from fleet_async.core.actions.action_queue import ActionQueue
from fleet_async.core.agents.agent_plugins import AgentPlugin, BatteryPlugin
from fleet_async.core.agents.batteries import BatteryBank
from fleet_async.core.agents.controller_schedule import ControllerSchedule
from fleet_async.core.base.compiled import use_numba
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
        self._compiled = use_numba(sim.params.kernels)
        self.engine = KinematicEngine(sim.state, self._on_motion_end, self._compiled)
        self.actions = ActionQueue(sim)
        self._slot_agent: dict[int, Agent] = {}
        self._controlled = ControllerSchedule()
        self._plugged: dict[int, list[AgentPlugin]] = {}
        self._limits: dict[tuple[Any, ...], MotionLimits] = {}
        self._dt = sim.params.timestep
        self.batteries = BatteryBank(
            self._battery_clock, self._dt, sim.state, compiled=self._compiled
        )
        self._battery_of: dict[int, list[BatteryPlugin]] = {}
        self._driven_step = -1
        self._reference = False
        self._still = False  # the last battery pass found no robot with a velocity

    @property
    def compiled(self) -> bool:
        """Whether the compiled (numba) kernels drive the engine (``SimulationParams.kernels``)."""
        return self._compiled

    @property
    def reference_path(self) -> bool:
        """Whether batteries are stepped robot by robot (the reference the numpy pass is
        tested against) instead of in one numpy pass. Both give the same bits."""
        return self._reference

    @reference_path.setter
    def reference_path(self, value: bool) -> None:
        self._reference = self._controlled.reference = bool(value)
        agents = [*self._agents_with_batteries(), *self._controlled.agents()]
        for agent in {id(a): a for a in agents}.values():
            self.track(agent)

    def _agents_with_batteries(self) -> list[Agent]:
        return [pl.agent for plugins in self._battery_of.values() for pl in plugins[:1]]

    def _battery_clock(self) -> int:
        """Steps the batteries are current at: the step's end once this step drove them."""
        step = self._sim.step_count
        return step + 1 if self._driven_step == step and self._sim.in_step else step

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
        """Store rows of the agents the safety fields watch (an array): those following a
        path or a velocity command on a built-in controller (a custom base controller moves
        its robot itself, so the fields cannot hold it; docs/traffic.md)."""
        return self.engine.commanded_rows()

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
        self._controlled.track(agent, agent.has_stepped_controllers())
        self._track_batteries(agent)
        stepped = [pl for pl in agent.plugins if self._needs_step(pl)]
        if stepped:
            self._plugged[key] = stepped
        elif key in self._plugged:
            del self._plugged[key]

    def _needs_step(self, plugin: AgentPlugin) -> bool:
        if isinstance(plugin, BatteryPlugin):
            return self._reference or plugin.steps_per_agent
        return type(plugin).on_step is not AgentPlugin.on_step

    def _track_batteries(self, agent: Agent) -> None:
        """Move ``agent``'s batteries into the bank, and the ones it dropped out of it."""
        key = agent.object_id
        now = [pl for pl in agent.plugins if isinstance(pl, BatteryPlugin)]
        for old in self._battery_of.get(key, ()):
            if not any(old is pl for pl in now):
                old.leave_bank()
        bank = self.batteries
        for pl in now:
            vector = not self._needs_step(pl)
            if pl.bank is not bank:
                pl.move_to(bank, agent.state_row, vector)
            else:
                bank.set_vector(pl.bank_slot, vector)
        self._still = False
        if now:
            self._battery_of[key] = now
        else:
            self._battery_of.pop(key, None)

    def forget(self, agent: Agent) -> None:
        """Drop everything held for ``agent`` (it left the simulation)."""
        self.actions.forget(agent)
        self._controlled.forget(agent)
        self._plugged.pop(agent.object_id, None)
        for battery in self._battery_of.pop(agent.object_id, ()):
            battery.leave_bank()

    def reset(self) -> None:
        """Forget every agent (simulation reset)."""
        self.engine = KinematicEngine(self._sim.state, self._on_motion_end, self._compiled)
        self.actions.reset()
        self._slot_agent.clear()
        self._controlled.clear()
        self._plugged.clear()
        self.batteries = BatteryBank(
            self._battery_clock, self._dt, self._sim.state, compiled=self._compiled
        )
        self._battery_of.clear()
        self._driven_step = -1
        self._still = False

    def advance(self, dt: float) -> None:
        """The agents' share of one step's motion phase."""
        self._dt = dt
        self.actions.tick(self._sim.sim_time, dt)
        if self._controlled:
            self._controlled.run(
                self.engine, self._sim.step_count, self._sim.sim_time, dt, self.actions.current
            )
        if not self.engine.is_idle():  # an idle fleet's step costs no array work
            self.engine.advance(dt)
        step = self._sim.step_count
        self._driven_step = step  # from here on, batteries are read at the step's end
        if not (self._still and self.engine.is_idle() and not self._controlled.polls_every_step):
            # Velocities change only through the engine, a stepped controller or physics; a
            # fleet that was found still and has none of them running is still.
            self._still = not self.batteries.drive(step) and not self._sim.params.physics
        for plugins in tuple(self._plugged.values()):
            for plugin in plugins:
                plugin.on_step(dt)
        # Last: a wait that ends with this step has covered all of it (a charge charged).
        self.actions.expire(self._sim.sim_time + dt, dt)

    def idle_steps(self, step: int, limit: int) -> int:
        """How many steps from ``step`` on (at most ``limit``) change no agent: nothing moves,
        no per-agent controller or plugin runs, and no action is due (see ActionQueue)."""
        if self._plugged or self._controlled.polls_every_step or not self.engine.is_idle():
            return 0
        dt = self._sim.params.timestep
        return self._controlled.idle_steps(step, dt, self.actions.idle_steps(step, dt, limit))

    def skip(self, last_step: int) -> None:
        """Steps up to ``last_step`` were skipped as empty."""
        self.actions.skip(last_step * self._sim.params.timestep)
        self._controlled.skipped(last_step + 1)

    def motion_ended(self, agent: Agent, reached: bool) -> None:
        """Record that ``agent`` stopped and wake an action waiting for it.

        Built-in controllers report through the engine; a custom base controller calls this
        (via ``agent.report_motion_end``) itself.
        """
        agent.note_motion_end(reached)
        self.wake_action(agent)

    def wake_action(self, agent: Agent) -> None:
        """Let the action ``agent`` waits on check its condition again (its joints moved)."""
        if not self.actions.waits_on_motion(agent):
            return
        now = self._sim.sim_time + self._dt if self._sim.in_step else self._sim.sim_time
        self.actions.on_motion_end(agent, now, self._dt)

    def _on_motion_end(self, slot: int, reached: bool) -> None:
        agent = self._slot_agent.get(slot)
        if agent is not None:
            self.motion_ended(agent, reached)
