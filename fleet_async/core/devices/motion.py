"""Timed device motion: a door leaf or a lift platform moving over an exact number of steps.

A device moves along one scalar coordinate ``s`` (a door's openness in [0, 1], a platform's
height in metres) from ``s0`` to ``s1`` in ``ceil(duration / dt)`` steps, linearly in sim time;
the device turns ``s`` into a pose (``apply_motion``). :class:`DeviceMotion` is the motion
system (``sim.add_motion_system``) that advances every moving device in one step's motion
phase, in ascending object id, after the robots; when a device arrives it wakes the action the
device is running, so that action ends at the end of that step (as a robot's move does).
Attached objects (a lift's passengers) follow in the step's attachment phase.

Device timing does not depend on the robots' motion profile: a door with ``open_time=2.0``
opens in exactly 2.0 s of sim time, whatever the controllers do.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, cast

from fleet_async.core.actions.action import Action, WaitHint
from fleet_async.core.base.steps import steps_for

if TYPE_CHECKING:
    from fleet_async.core.actions.host import ActingAgent
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["DeviceAction", "DeviceMotion", "MovingDevice"]


class _Keyed(Protocol):
    object_id: int


class MovingDevice(Protocol):
    """What :class:`DeviceMotion` needs from a device (an Agent subclass)."""

    object_id: int

    def apply_motion(self, s: float) -> None:
        """Put the device where coordinate ``s`` says (pose, state fields)."""

    def motion_finished(self) -> None:
        """The device reached the end of its motion (called after the last ``apply_motion``)."""


@dataclass
class _Move:
    device: MovingDevice
    s0: float
    s1: float
    steps: int
    done: int = 0


@dataclass
class DeviceMotion:
    """Advances every moving device of one simulation (one per simulation: :meth:`of`)."""

    sim: SimulationKernel
    _moves: dict[int, _Move] = field(default_factory=dict)

    @classmethod
    def of(cls, sim: SimulationKernel) -> DeviceMotion:
        """The simulation's device motion system, registered with it on first use."""
        motion = _SYSTEMS.get(sim)
        if motion is None:
            motion = _SYSTEMS[sim] = cls(sim)
            sim.add_motion_system(motion)
        return motion

    def start(self, device: MovingDevice, s0: float, s1: float, duration: float) -> bool:
        """Move ``device`` from ``s0`` to ``s1`` in ``duration`` seconds (rounded up to steps).

        Returns:
            True if there is nothing to do (no distance or no time): the device was put at
            ``s1`` at once and ``motion_finished`` was called.
        """
        steps = max(0, steps_for(duration, self.sim.params.timestep))
        self._moves.pop(device.object_id, None)
        if steps == 0 or s0 == s1:
            device.apply_motion(s1)
            device.motion_finished()
            return True
        self._moves[device.object_id] = _Move(device, s0, s1, steps)
        return False

    def stop(self, device: _Keyed) -> bool:
        """Stop ``device`` where it is; return whether it was moving."""
        return self._moves.pop(device.object_id, None) is not None

    def is_moving(self, device: _Keyed) -> bool:
        """Whether ``device`` is on its way."""
        return device.object_id in self._moves

    def advance(self, dt: float) -> None:
        """One step of every moving device, in ascending object id."""
        if not self._moves:
            return
        for key in sorted(self._moves):
            move = self._moves[key]
            move.done += 1
            u = move.done / move.steps
            move.device.apply_motion(move.s1 if u >= 1.0 else move.s0 + (move.s1 - move.s0) * u)
            if move.done >= move.steps:
                del self._moves[key]
                move.device.motion_finished()
                agent: Agent = move.device  # type: ignore[assignment]  # devices are Agents
                self.sim.fleet.wake_action(agent)


_SYSTEMS: weakref.WeakKeyDictionary[SimulationKernel, DeviceMotion] = weakref.WeakKeyDictionary()


@dataclass(eq=False)
class DeviceAction(Action):
    """Base of the actions a device runs from its own queue (door open/close, lift trip).

    The first ``execute`` asks the device to start (``begin``); the action then waits for the
    device's motion to end, like a robot's move, and ends at the end of the step the device
    arrives in. Cancelling it stops the device where it is (``halt``).
    """

    _started: bool = field(default=False, init=False, repr=False)

    def execute(self, agent: ActingAgent, dt: float) -> bool:
        """Start the device on the first call; complete when its motion has ended."""
        device = cast("Agent", agent)  # a device runs its actions on itself, an Agent
        if not self._started:
            self._started = True
            return self.begin(device)
        return not DeviceMotion.of(self._sim_of(device)).is_moving(device)

    def begin(self, agent: Agent) -> bool:
        """Start the motion; return True if it is already over (subclasses)."""
        raise NotImplementedError

    def halt(self, agent: Agent) -> None:  # optional hook, empty by default
        """The action was cancelled while the device moved (subclasses clean up)."""

    def wait_hint(self) -> WaitHint:
        """Waits for the end of the device's motion."""
        return ("motion", None)

    def on_cancel(self, agent: ActingAgent) -> None:
        """Stop the device where it is."""
        if self._started:
            device = cast("Agent", agent)  # a device runs its actions on itself, an Agent
            DeviceMotion.of(self._sim_of(device)).stop(device)
            self.halt(device)

    def reset(self) -> None:
        """Forget progress."""
        self._reset_status()
        self._started = False

    @staticmethod
    def _sim_of(agent: Agent) -> SimulationKernel:
        sim = agent.sim_core
        if sim is None:
            raise ValueError(f"{agent!r} is not part of a simulation")
        return cast("SimulationKernel", sim)  # a device's simulation: see Device.sim_core
