"""Device: the base of doors, elevators and workcells, an Agent with spawn params of its own.

A device is an Agent (it has an action queue, so its commands are actions that missions await
with ``agent.submit``), fixed in place for the robots' motion controllers, and built from its
own spawn params dataclass (``cls._spawn_params_cls``, as the reference API's note on Door and
Elevator says): ``Door.from_dict({...})`` and ``type: door`` entries in a scenario both go
through :meth:`Device.from_params`. Its body moves only through the device motion system
(``motion.py``). State changes are emitted on ``sim.events`` and on the device's own bus.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar, cast

import pybullet as p

from fleet_async.core.agents.agent import Agent
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.bodies.spawning import create_body
from fleet_async.core.devices.motion import DeviceMotion

if TYPE_CHECKING:
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["Device"]


class Device(Agent):
    """Base class of devices; subclasses set ``_spawn_params_cls`` and :meth:`setup`.

    Build devices with ``from_params`` / ``from_dict`` (or a scenario entry), not with the
    constructor or the robot factories (``from_mesh``, ``from_urdf``).
    """

    _spawn_params_cls: ClassVar[type[AgentSpawnParams]] = AgentSpawnParams
    device_type: ClassVar[str] = "device"
    """The scenario ``type:`` name of this device class."""
    is_robot: ClassVar[bool] = False  # the fleet's KPIs leave devices out
    sim_core: SimulationKernel | None
    """The simulation the device is in: devices stand above the kernel and use more of it
    than an agent does (the step count, poses in bulk, the mission waits, motion systems)."""

    @classmethod
    def from_params(  # type: ignore[override]  # takes the device's own params
        cls, spawn_params: AgentSpawnParams, sim_core: SimulationKernel | None = None
    ) -> Device:
        """Create the device described by ``spawn_params`` (an instance of
        ``cls._spawn_params_cls``).

        Raises:
            TypeError: for params of another class.
            ValueError: for bad parameters.
        """
        expected = cls._spawn_params_cls
        if not isinstance(spawn_params, expected):
            raise TypeError(
                f"{cls.__name__}.from_params: expected {expected.__name__}, "
                f"got {type(spawn_params).__name__}"
            )
        if sim_core is None:
            raise ValueError(f"{cls.__name__}.from_params: a device needs a simulation (sim_core)")
        params = cls.complete_params(spawn_params)
        DeviceMotion.of(sim_core)  # registered now, so a motion started in a step moves in it
        body = create_body(params, sim_core)
        device: Device | None = None
        try:
            device = cls(
                body,
                use_fixed_base=True,
                collision_mode=params.collision_mode,
                sim_core=sim_core,
                name=params.name,
                user_data=dict(params.user_data),
                mass=0.0,
                controller=params.controller,
                notify_spawn=False,
            )
            device.setup(params)
        except Exception:
            if device is not None and device.sim_core is not None:
                sim_core.remove_object(device)  # never leave a half-built device behind
            else:
                p.removeBody(body, physicsClientId=sim_core.client)
            raise
        finished = cls._finish_spawn(device, params, sim_core)
        assert isinstance(finished, Device)
        return finished

    @classmethod
    def spawn_batch(  # type: ignore[override]  # devices spawn one by one
        cls, params_list: Sequence[AgentSpawnParams], sim_core: SimulationKernel
    ) -> list[Device]:
        """Spawn devices one by one (in order); if one fails, the others are removed."""
        made: list[Device] = []
        try:
            for params in params_list:
                made.append(cls.from_params(params, sim_core))
        except BaseException:
            for device in reversed(made):
                sim_core.remove_object(device)
            raise
        return made

    @classmethod
    def from_mesh(cls, *args: Any, **kwargs: Any) -> Device:
        """Not for devices.

        Raises:
            TypeError: always; use ``from_params`` or ``from_dict``.
        """
        raise TypeError(f"{cls.__name__}: build devices with from_params or from_dict")

    @classmethod
    def from_urdf(cls, *args: Any, **kwargs: Any) -> Device:
        """Not for devices.

        Raises:
            TypeError: always; use ``from_params`` or ``from_dict``.
        """
        raise TypeError(f"{cls.__name__}: build devices with from_params or from_dict")

    @classmethod
    def complete_params(cls, params: AgentSpawnParams) -> AgentSpawnParams:
        """``params`` with what the device fills in itself (default shapes); subclasses."""
        return params

    def setup(self, params: AgentSpawnParams) -> None:
        """Read the device's own fields from ``params`` (subclasses; called once, before the
        spawn events)."""

    def apply_motion(self, s: float) -> None:
        """Put the device at motion coordinate ``s`` (subclasses that move)."""
        raise NotImplementedError(f"{type(self).__name__} does not move")

    def motion_finished(self) -> None:
        """The device motion system brought the device to the end of its motion."""

    # ----- helpers for subclasses ---------------------------------------------------------

    def _require_sim(self, what: str) -> SimulationKernel:
        # The same check as SimObject's; a device's simulation is a kernel (see ``sim_core``).
        return cast("SimulationKernel", super()._require_sim(what))

    @property
    def device_motion(self) -> DeviceMotion:
        """The simulation's device motion system."""
        return DeviceMotion.of(self._require_sim(f"{type(self).__name__} motion"))

    def emit(self, event: str, **payload: Any) -> None:
        """Emit ``event`` on the simulation's bus and, if it exists, on this device's own."""
        sim = self.sim_core
        if sim is not None:
            sim.events.emit(event, **payload)
        if self.has_event_bus():
            self.events.emit(event, **payload)

    def on_removed(self) -> None:
        """Stop moving, then leave the fleet."""
        sim = self.sim_core
        if sim is not None:
            DeviceMotion.of(sim).stop(self)
        super().on_removed()
