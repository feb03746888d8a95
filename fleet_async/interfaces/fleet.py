"""The fleet interface: robots served to masters in other processes, at step boundaries.

A :class:`FleetInterface` makes some robots of a simulation *served vehicles*. Commands
(:mod:`~fleet_async.interfaces.commands`) arrive from any thread at any wall-clock moment
through :meth:`FleetInterface.submit`; they wait in an inbox and are applied at the next step
boundary (the simulation's PRE_STEP), in arrival order, then each vehicle follows up on what it
is doing. A traced run records every applied command with its step, so
:func:`replay_commands` reproduces the run with no network at all.

What the vehicles report goes to listeners (:class:`FleetListener`), called on the simulation's
thread at the step boundary with immutable snapshots: a state when something the master must
hear of happened (never for a pose change alone) and at least every ``state_period`` s of sim
time; a visualization snapshot every ``visualization_period`` s. A listener that talks to a
network only hands the snapshot over (a transport's own thread publishes it), so a step never
waits for a network.
"""

from __future__ import annotations

import logging
import threading
from collections import defaultdict, deque
from collections.abc import Iterable, Sequence
from typing import Any, Protocol

import numpy as np

from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.steps import steps_for
from fleet_async.interfaces.commands import Command, command_from_json
from fleet_async.interfaces.host import ServingHost
from fleet_async.interfaces.snapshot import VehiclePose, VehicleSnapshot
from fleet_async.interfaces.vehicle import Vehicle

__all__ = ["FleetInterface", "FleetListener", "replay_commands", "trace_state"]

logger = logging.getLogger(__name__)


class FleetListener(Protocol):
    """Hears what served vehicles report (a transport, a test, a log)."""

    def on_state(self, snapshot: VehicleSnapshot, reasons: tuple[str, ...]) -> None:
        """A state to report: ``reasons`` says why (``("periodic",)`` for the timer)."""

    def on_visualization(self, pose: VehiclePose) -> None:
        """A pose update at the visualization rate."""

    def on_factsheet_request(self, vehicle: str) -> None:
        """The master asked for ``vehicle``'s description."""


def _steps(seconds: float, timestep: float) -> int:
    return max(1, steps_for(seconds, timestep))  # a period shorter than a step: every step


class FleetInterface:
    """Serve ``robots`` of ``sim`` to fleet masters.

    Args:
        sim: The simulation (a ``MultiRobotSimulationCore``).
        robots: Names of the robots to serve (default: every agent). Each must name exactly
            one agent.
        state_period: s of sim time between states when nothing happens (<= 30 s, as fleet
            protocols ask).
        visualization_period: s of sim time between visualization snapshots (0: none).
        deviation_xy: m within which a node counts as reached when an order does not say.
        driver: Who drives the robots, for the error a mission gets if it commands one.

    Raises:
        ValueError: for an unknown or ambiguous robot name, or a period out of range.
    """

    def __init__(
        self,
        sim: ServingHost,
        robots: Sequence[str] | None = None,
        *,
        state_period: float = 30.0,
        visualization_period: float = 0.1,
        deviation_xy: float = 0.5,
        driver: str = "a fleet master (fleet interface)",
    ) -> None:
        if not 0 < state_period <= 30.0:
            raise ValueError(
                f"FleetInterface.state_period: expected a number in (0, 30] s, got {state_period!r}"
            )
        if not visualization_period >= 0:
            raise ValueError(
                "FleetInterface.visualization_period: expected a number >= 0 s, "
                f"got {visualization_period!r}"
            )
        self.sim = sim
        dt = sim.params.timestep
        self._state_every = _steps(state_period, dt)
        self._viz_every = _steps(visualization_period, dt) if visualization_period > 0 else 0
        self.vehicles: dict[str, Vehicle] = {}
        self._reasons: dict[str, list[str]] = defaultdict(list)
        # Vehicles with work in progress, and those with news: a step looks at these only, so
        # a served fleet that mostly waits costs nothing per idle vehicle.
        self._active: set[str] = set()
        self._changed: set[str] = set()
        for name, agent in self._select(sim, robots):
            vehicle = Vehicle(agent, sim, deviation_xy, self._change_hook(name), name=name)
            agent.external_driver = driver
            self.vehicles[name] = vehicle
        self._index = {name: i for i, name in enumerate(self.vehicles)}  # the served order
        self._inbox: deque[tuple[str, Command]] = deque()
        self._lock = threading.Lock()
        self._scheduled: dict[int, list[tuple[str, Command]]] = defaultdict(list)
        self._listeners: list[FleetListener] = []
        self._closed = False
        sim.events.on(SimEvents.PRE_STEP, self._on_pre_step)
        # A safety stop starting or ending changes the state (driving, fieldViolation).
        self._name_of = {id(v.agent): name for name, v in self.vehicles.items()}
        sim.events.on(SimEvents.SAFETY_STOP_STARTED, self._on_safety)
        sim.events.on(SimEvents.SAFETY_STOP_ENDED, self._on_safety)

    @staticmethod
    def _select(sim: Any, robots: Sequence[str] | None) -> list[tuple[str, Any]]:
        """``(vehicle name, agent)`` of the served robots: a robot's name, or ``name#id``
        where several robots share it (``#id`` for a robot without one)."""
        agents = list(sim.agents)
        by_name: dict[str, list[Any]] = defaultdict(list)
        for agent in agents:
            by_name[agent.name or ""].append(agent)
        if robots is None:
            return [
                (
                    agent.name
                    if agent.name and len(by_name[agent.name]) == 1
                    else f"{agent.name or ''}#{agent.object_id}",
                    agent,
                )
                for agent in agents
            ]
        chosen = []
        for name in robots:
            found = by_name.get(name, [])
            if len(found) != 1:
                problem = "no robot" if not found else f"{len(found)} robots"
                known = ", ".join(sorted(by_name)[:20])
                raise ValueError(
                    f"FleetInterface.robots: {name!r} names {problem} (robots: {known})"
                )
            chosen.append((name, found[0]))
        return chosen

    def _change_hook(self, name: str) -> Any:
        reasons, changed = self._reasons[name], self._changed

        def note(reason: str) -> None:
            reasons.append(reason)
            changed.add(name)

        return note

    # ----- the master's side ------------------------------------------------------------------

    def submit(self, vehicle: str, command: Command) -> None:
        """Queue ``command`` for ``vehicle``; it is applied at the next step boundary.

        Safe to call from any thread (a transport's network thread).

        Raises:
            KeyError: for a vehicle this interface does not serve.
        """
        if vehicle not in self.vehicles:
            raise KeyError(f"FleetInterface.submit: {vehicle!r} is not a served vehicle")
        with self._lock:
            self._inbox.append((vehicle, command))

    def schedule(self, step: int, vehicle: str, command: Command) -> None:
        """Apply ``command`` at the boundary where the step count is ``step`` (a replay)."""
        if vehicle not in self.vehicles:
            raise KeyError(f"FleetInterface.schedule: {vehicle!r} is not a served vehicle")
        self._scheduled[int(step)].append((vehicle, command))

    def add_listener(self, listener: FleetListener) -> None:
        """Report to ``listener`` from now on."""
        self._listeners.append(listener)

    def remove_listener(self, listener: FleetListener) -> None:
        """Stop reporting to ``listener``."""
        if listener in self._listeners:
            self._listeners.remove(listener)

    def snapshot(self, vehicle: str) -> VehicleSnapshot:
        """``vehicle``'s state now."""
        return self.vehicles[vehicle].snapshot()

    def close(self) -> None:
        """Stop serving: the robots may be driven by missions again."""
        if self._closed:
            return
        self._closed = True
        self.sim.events.off(SimEvents.PRE_STEP, self._on_pre_step)
        self.sim.events.off(SimEvents.SAFETY_STOP_STARTED, self._on_safety)
        self.sim.events.off(SimEvents.SAFETY_STOP_ENDED, self._on_safety)
        for vehicle in self.vehicles.values():
            vehicle.agent.external_driver = None

    # ----- the step boundary ----------------------------------------------------------------

    def _on_safety(self, agent: Any, **_: Any) -> None:
        name = self._name_of.get(id(agent))
        if name is not None:
            self._reasons[name].append("field_violation")
            self._changed.add(name)

    def _on_pre_step(self, step: int, **_: Any) -> None:
        with self._lock:
            arrived = list(self._inbox)
            self._inbox.clear()
        due = self._scheduled.pop(step, [])
        tracer = self.sim.tracer
        for name, command in (*due, *arrived):
            if tracer is not None:
                tracer.command(step, name, command.to_json())
            self.vehicles[name].apply(command)
            self._active.add(name)
        for name in self._in_order(self._active):
            vehicle = self.vehicles[name]
            vehicle.advance()
            if not vehicle.busy:
                self._active.discard(name)
        self._report(step)

    def _in_order(self, names: set[str]) -> list[str]:
        """``names`` in the served order (a set's order is not deterministic)."""
        return sorted(names, key=self._index.__getitem__)

    def _trace_states(self) -> None:
        """A ``vehicle_state`` trace event for each vehicle whose order or tasks changed."""
        tracer = self.sim.tracer
        if tracer is None:
            return
        for name in self._in_order(self._changed):
            vehicle = self.vehicles[name]
            tracer.event("vehicle_state", vehicle.agent.object_id, **trace_state(vehicle))

    def _report(self, step: int) -> None:
        self._trace_states()
        changed = self._in_order(self._changed)
        periodic = step % self._state_every == 0
        if self._listeners:
            for name in self.vehicles if periodic else changed:
                self._report_state(name)
            if self._viz_every and step % self._viz_every == 0:
                for pose in self.poses():
                    for listener in self._listeners:
                        listener.on_visualization(pose)
        for name in changed:
            self._reasons[name].clear()
        self._changed.clear()

    def _report_state(self, name: str) -> None:
        vehicle, reasons = self.vehicles[name], self._reasons[name]
        snap = vehicle.snapshot()
        why = tuple(dict.fromkeys(reasons)) if reasons else ("periodic",)
        for listener in self._listeners:
            listener.on_state(snap, why)
        if vehicle.factsheet_requested:
            vehicle.factsheet_requested = False
            for listener in self._listeners:
                listener.on_factsheet_request(name)

    def poses(self) -> list[VehiclePose]:
        """Every served vehicle's pose and velocity now, read from the state store at once."""
        sim = self.sim
        store = sim.state
        rows = np.fromiter(
            (v.agent.state_row for v in self.vehicles.values()), np.int64, len(self.vehicles)
        )
        qx, qy, qz, qw = store.orientation[rows].T
        yaw = np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
        velocity = store.velocity[rows]
        c, s = np.cos(yaw), np.sin(yaw)
        columns = (
            store.position[rows, 0].tolist(),
            store.position[rows, 1].tolist(),
            yaw.tolist(),
            (c * velocity[:, 0] + s * velocity[:, 1]).tolist(),
            (c * velocity[:, 1] - s * velocity[:, 0]).tolist(),
            store.angular_velocity[rows, 2].tolist(),
        )
        step, now = sim.step_count, sim.sim_time
        return [
            VehiclePose(name, step, now, *values)
            for name, *values in zip(self.vehicles, *columns, strict=True)
        ]


def trace_state(vehicle: Vehicle) -> dict[str, Any]:
    """What the trace's ``vehicle_state`` event says of ``vehicle`` (docs/trace-format.md)."""
    snap = vehicle.snapshot()
    return {
        "vehicle": snap.name,
        "order_id": snap.order_id,
        "order_update": snap.order_update,
        "last_node": snap.last_node_id,
        "nodes": [
            [n, seq, rel, round(x, 4), round(y, 4)]
            for (n, seq, rel), (x, y) in zip(snap.nodes, snap.node_positions, strict=True)
        ],
        "edges": [[e, seq, rel] for e, seq, rel in snap.edges],
        "tasks": [[t.task_id, t.kind, t.status.value] for t in snap.tasks],
        "paused": snap.paused,
        "errors": [[e.kind, e.description] for e in snap.errors],
    }


def replay_commands(sim: Any, trace: Any, robots: Iterable[str] | None = None) -> FleetInterface:
    """Serve ``sim``'s robots with the commands a trace recorded, at their steps.

    Args:
        sim: A simulation built as the traced one was, at step 0.
        trace: A ``fleet_async.viewer.TraceReader`` or a trace's path.
        robots: The served robots (default: every vehicle the trace names).

    Returns:
        The fleet interface, with every command scheduled: step the simulation as before.
    """
    if not hasattr(trace, "commands"):
        from fleet_async.viewer.reader import TraceReader

        trace = TraceReader(trace)
    records = list(trace.commands)
    names = list(robots) if robots is not None else sorted({r["vehicle"] for r in records})
    fleet = FleetInterface(sim, names)
    for record in records:
        fleet.schedule(record["step"], record["vehicle"], command_from_json(record["command"]))
    return fleet
