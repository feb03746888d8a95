"""Agent commands for async missions: each queues the matching Action and returns its event.

``agent.move(path)`` queues a MoveAction at once and returns an event for it (the runtime's
``ActionWait``): ``await`` it to wait for the end; it returns the finished action, raises
ActionFailedError (with ``.action`` and its ``error_message``) when it FAILED, and
ActionCancelledError when something outside the mission cancelled it. The event is also a
handle (``cancel()``, ``status``, ``phase``, ``progress``) and composes with ``sim.any_of``.
Cancelling a mission that awaits it (a task group, a sim-time timeout, a race it lost, an
interrupt) cancels the action: a queued one is dropped, a running one stops the robot in that
step.

An action a mission queues this way belongs to that mission: when the mission ends (it
returns, fails or is cancelled) its unfinished actions are cancelled, so nothing drives on
for a mission that stopped caring. ``detached=True`` makes the fire-and-forget form: the
action outlives its mission, and its failure is logged and traced but fails nothing.
``agent.add_action`` keeps the seed's semantics (the queue owns the action).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from fleet_async.core.actions.action import Action, MoveAction, WaitAction
from fleet_async.core.actions.arm_actions import JointAction, PoseAction
from fleet_async.core.actions.pick_drop import DropAction, PickAction
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.waypoints import Path
from fleet_async.core.missions.errors import ExternallyDrivenError
from fleet_async.core.routes.api import graph_of
from fleet_async.core.routes.follow import route_to_node

if TYPE_CHECKING:
    from fleet_async.core.missions.host import MissionAgent
    from fleet_async.core.missions.mission_api import MissionRuntime

__all__ = ["AgentMissionApi"]

_MAX_CHARGE_STEPS = 10_000_000
"""Steps a charge to a level may take at most (beyond: the rate is too small to be meant)."""


def _time_to_charge(battery: Any, to: float, agent: MissionAgent) -> float:
    """Sim seconds of charging standing still that bring ``battery`` to ``to``: the whole
    steps the battery's own per-step update (charge rate less drain over time, capped at
    1) needs, counted with the same arithmetic.

    Raises:
        ValueError: for ``to`` outside [0, 1], or a battery that cannot reach it.
    """
    if isinstance(to, bool) or not isinstance(to, (int, float)) or not 0.0 <= to <= 1.0:
        raise ValueError(f"agent.charge: to must be a state of charge in [0, 1], got {to!r}")
    sim = agent.sim_core
    dt = sim.params.timestep if sim is not None else 0.0
    # The battery counts with its own formula (a charging robot standing still).
    steps = battery.charging_steps_to(to, dt, _MAX_CHARGE_STEPS)
    if steps is None:
        raise ValueError(
            f"agent.charge: {agent.name!r}'s battery drains {battery.drain_per_second}/s and "
            f"charges {battery.charge_rate}/s, so it cannot reach {to} by charging"
        )
    if steps == 0:
        return 0.0
    return (steps - 0.5) * dt  # a wait ends at the first step it covers: exactly ``steps``


class AgentMissionApi:
    """Mixin for Agent: ``await agent.move(...)``, ``pick``, ``drop``, ``wait``, ``charge``,
    ``move_joints``, ``reach_pose``, ``submit``. Each queues its action when called and
    returns an event for it."""

    external_driver: str | None = None
    """Who drives this agent from outside the simulation (a served fleet's master), or None.

    While set, mission commands to the agent are refused: two drivers would fight over its
    action queue. Set by a fleet interface (``fleet_async.interfaces``) when it serves the agent.
    """

    def _mission_runtime(self, what: str) -> MissionRuntime:
        agent: MissionAgent = self  # type: ignore[assignment]  # mixed into Agent, a MissionAgent
        agent.check_not_removed(what)  # "needs a running mission" would mislead
        if self.external_driver is not None:
            raise ExternallyDrivenError(
                f"{what}: {agent.name!r} is driven by {self.external_driver}; a mission cannot "
                "command it (leave it out of the served robots to drive it from a mission)"
            )
        sim = agent.sim_core
        if sim is None:
            raise ValueError(f"{what}: {agent.name!r} is not in a simulation")
        return sim.ensure_mission_runtime()

    def submit(self, action: Action, *, detached: bool = False, what: str = "agent.submit") -> Any:
        """Queue ``action`` now and return its event: ``await`` it to wait for the end,
        ``cancel()`` it, or watch ``status``, ``phase`` and ``progress``.

        Args:
            action: The action to queue.
            detached: Let the action outlive the mission that queued it (fire and forget):
                it is not cancelled when the mission ends, and its failure is only logged
                and traced.
            what: How messages name the call (``agent.move`` ...).
        """
        runtime = self._mission_runtime(what)
        agent: MissionAgent = self  # type: ignore[assignment]  # mixed into Agent, a MissionAgent
        action.awaited = True  # e.g. a move on a fixed base fails rather than being skipped
        agent.add_action(action)
        return runtime.wait_action(agent, action, detached=detached, what=what)

    def move(
        self, path: Path | Pose | list[Pose], *, detached: bool = False, **options: Any
    ) -> Any:
        """Follow ``path``; options as MoveAction (auto_approach, direction, ...)."""
        if not isinstance(path, (Path, Pose, list, tuple)) and isinstance(path, Iterable):
            path = list(path)  # MoveAction names what it got when this is not Poses
        action = MoveAction(path=path, **options)  # type: ignore[arg-type]  # takes a Pose too
        return self.submit(action, detached=detached, what="agent.move")

    def go_to_node(self, node_id: str, *, detached: bool = False) -> Any:
        """Drive the quickest route of the simulation's route graph from the nearest node to
        ``node_id``, each edge at its speed limit (``routes/follow.py``)."""
        action = route_to_node(self, graph_of(self), node_id)
        return self.submit(action, detached=detached, what="agent.go_to_node")

    def pick(self, target: Any = None, *, detached: bool = False, **options: Any) -> Any:
        """Pick ``target`` (a SimObject or body id), or pass PickAction options such as
        ``target_position`` and ``search_radius``."""
        if target is not None:
            options["target_object_id"] = target
        return self.submit(PickAction(**options), detached=detached, what="agent.pick")

    def drop(self, drop_pose: Pose, *, detached: bool = False, **options: Any) -> Any:
        """Drop what is carried at ``drop_pose`` (DropAction options)."""
        action = DropAction(drop_pose=drop_pose, **options)
        return self.submit(action, detached=detached, what="agent.drop")

    def wait(self, duration: float, action_type: str = "idle", *, detached: bool = False) -> Any:
        """Stand still for ``duration`` sim seconds as a queued WaitAction."""
        action = WaitAction(duration=duration, action_type=action_type)
        what = "agent.charge" if action_type == "charge" else "agent.wait"
        return self.submit(action, detached=detached, what=what)

    def charge(self, duration: float | None = None, *, to: float | None = None) -> Any:
        """Charge the battery for ``duration`` sim seconds, or until its state of charge
        reaches ``to`` (in [0, 1]): the whole steps that take it there standing still, at
        the battery's charge rate less its drain over time (a wait of 0 if it is there
        already).

        Raises:
            ValueError: if the agent has no battery (charging would only wait), saying how to
                give it one; for not exactly one of ``duration`` and ``to``, a ``to`` outside
                [0, 1], or a battery that cannot get there (it drains faster than it charges).
        """
        agent: MissionAgent = self  # type: ignore[assignment]  # mixed into Agent, a MissionAgent
        battery = agent.battery_plugin
        if battery is None:
            raise ValueError(
                f"agent.charge: {agent!r} has no battery, so charging would only wait. Give it "
                "one: in a scenario, 'plugins: [{type: battery, config: {initial_soc: 0.5}}]' "
                "on its entity; in Python, agent.add_plugin(BatteryPlugin(agent, "
                "{'initial_soc': 0.5})) or AgentSpawnParams(..., plugins=[{'type': "
                "'battery'}]). To wait without charging, use agent.wait(duration)"
            )
        if (duration is None) == (to is None):
            raise ValueError(
                "agent.charge: give a duration (charge(30.0)) or a level (charge(to=0.95)), "
                f"not {'both' if to is not None else 'neither'}"
            )
        if to is not None:
            return self.wait(_time_to_charge(battery, to, agent), action_type="charge")
        assert duration is not None  # exactly one of the two was given
        return self.wait(duration, action_type="charge")

    def move_joints(self, targets: Any, **options: Any) -> Any:
        """Move joints to ``targets`` (a list, or {joint name: position}) as a JointAction;
        options: ``max_force``, ``tolerance``."""
        action = JointAction(target_joint_positions=targets, **options)
        return self.submit(action, what="agent.move_joints")

    def reach_pose(self, position: Any, orientation: Any = None, **options: Any) -> Any:
        """Bring the end effector to ``position`` ([x, y, z], world frame) and optionally
        ``orientation`` ([qx, qy, qz, qw]) through IK, as a PoseAction (raises
        ActionFailedError when it is out of reach); options: ``end_effector_link``,
        ``max_force``, ``tolerance``."""
        action = PoseAction(target_position=position, target_orientation=orientation, **options)
        return self.submit(action, what="agent.reach_pose")
