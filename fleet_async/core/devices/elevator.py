"""Elevator: a platform that carries what stands on it between named floor heights.

State machine (``ElevatorState``): IDLE at a floor; MOVING while a trip runs; ARRIVED at the
end of the step it reaches its floor, IDLE one step later (or MOVING, if a queued trip starts).
Trips are actions on the lift's own queue (:class:`ElevatorTrip`), served first come, first
served, one at a time. A trip of h metres takes ``h / speed`` seconds (whole steps, rounded
up). When a trip starts, every object standing on the platform (its base above the platform
and under ``cabin_height``, not carried by something else, not static scenery) is attached to
the platform and rides along through the step's attachment phase; on arrival they are released
where they stand. Cancelling a trip stops the platform where it is and releases its passengers.

Commands:

- ``elevator.request_floor(name)`` (the reference API's): fire and forget, under the lift's
  ``request_policy`` (REJECT, REPLACE_NEXT, QUEUE) while it is busy; returns an
  ``ElevatorRequestResult``. An unknown floor is a ValueError.
- ``await elevator.go_to(name)``: queue a trip (always, whatever the policy) and wait for it.
- ``await elevator.ride(robot, name)``: the mission-layer composite (call, board, travel,
  alight) with the lift held as a sim-aware Resource (``fleet_async.tasks.devices``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.base.device_events import DeviceEvents
from fleet_async.core.base.types import ActionStatus, CollisionMode
from fleet_async.core.devices.device import Device
from fleet_async.core.devices.elevator_params import (
    ElevatorParams,
    ElevatorRequestPolicy,
    ElevatorRequestResult,
    ElevatorState,
)
from fleet_async.core.devices.motion import DeviceAction
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.quaternions import quat_to_rot_matrix
from fleet_async.core.missions.hooks import mission_hook
from fleet_async.core.world.shapes import ShapeParams

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.bodies.sim_object import SimObject

__all__ = ["Elevator", "ElevatorTrip"]

_EPS = 1e-6


@dataclass(eq=False)
class ElevatorTrip(DeviceAction):
    """Take the elevator that runs it to ``floor``."""

    floor: str = ""

    def begin(self, agent: Agent) -> bool:
        """Depart (attaching the passengers); True if the lift already is at ``floor``."""
        if not isinstance(agent, Elevator):
            return self.fail(f"ElevatorTrip runs on an Elevator, not {agent!r}")
        return agent.depart(self.floor)

    def halt(self, agent: Agent) -> None:
        """Stopped between floors: release the passengers there."""
        if isinstance(agent, Elevator):
            agent.halted()


class Elevator(Device):
    """A lift device; see the module docstring for its states and commands."""

    _spawn_params_cls: ClassVar[type[AgentSpawnParams]] = ElevatorParams
    device_type: ClassVar[str] = "elevator"

    _params: ElevatorParams
    _floors: dict[str, float]
    _current: str
    _target: str
    _state: ElevatorState = ElevatorState.IDLE
    _arrived_step: int = -1

    @classmethod
    def complete_params(cls, params: AgentSpawnParams) -> AgentSpawnParams:
        """Put the platform's top at the initial floor; give it its default box."""
        assert isinstance(params, ElevatorParams)
        assert params.floors is not None
        pose = params.initial_pose.copy()
        pose.position[2] = params.floors[params.initial_floor]
        changes: dict[str, Any] = {"initial_pose": pose}
        if params.visual_shape is None and params.collision_shape is None:
            sx, sy = params.platform_size
            half = [sx / 2, sy / 2, params.platform_thickness / 2]
            offset = Pose([0.0, 0.0, -params.platform_thickness / 2])
            changes |= {
                "visual_shape": ShapeParams("box", half_extents=half, rgba_color=params.rgba_color),
                "collision_shape": ShapeParams("box", half_extents=half),
                "visual_frame_pose": params.visual_frame_pose or offset,
                "collision_frame_pose": params.collision_frame_pose or offset,
            }
        return dataclasses.replace(params, **changes)

    def setup(self, params: AgentSpawnParams) -> None:
        """Read the floors and the policy."""
        assert isinstance(params, ElevatorParams)
        assert params.floors is not None
        self._params = params
        self._floors = dict(params.floors)
        self._current = self._target = params.initial_floor
        self._pending: list[ElevatorTrip] = []
        self._passengers: list[SimObject] = []

    # ----- state --------------------------------------------------------------------------

    @property
    def state(self) -> ElevatorState:
        """IDLE, MOVING or ARRIVED."""
        return self._state

    @property
    def is_moving(self) -> bool:
        """Whether a trip is under way."""
        return self._state is ElevatorState.MOVING

    @property
    def current_floor(self) -> str:
        """The floor the lift is at (the departure floor while moving)."""
        return self._current

    @property
    def target_floor(self) -> str:
        """Where the current trip goes (the current floor when not moving)."""
        return self._target

    @property
    def available_floors(self) -> list[str]:
        """Floor names, in the order given."""
        return list(self._floors)

    @property
    def floors(self) -> dict[str, float]:
        """Floor name -> platform height (m)."""
        return dict(self._floors)

    @property
    def request_policy(self) -> ElevatorRequestPolicy:
        """How ``request_floor`` treats requests while the lift is busy."""
        return self._params.request_policy

    @property
    def pending_floors(self) -> tuple[str, ...]:
        """Floors of the trips queued after the current one, in order."""
        self._pending = [t for t in self._pending if t.status is ActionStatus.NOT_STARTED]
        return tuple(t.floor for t in self._pending)

    @property
    def passengers(self) -> list[SimObject]:
        """Objects riding the current trip."""
        return list(self._passengers)

    @property
    def height(self) -> float:
        """Height of the platform's top, m."""
        return float(self.get_pose().z)

    @property
    def speed(self) -> float:
        """Platform speed, m/s."""
        return self._params.speed

    def floor_height(self, floor: str) -> float:
        """Height of ``floor`` (m).

        Raises:
            ValueError: for an unknown floor, naming the known ones.
        """
        self._check_floor(floor, "floor_height")
        return self._floors[floor]

    def is_at(self, floor: str) -> bool:
        """Whether the platform stands at ``floor``'s height (moving or not)."""
        return abs(self.height - self.floor_height(floor)) <= _EPS

    def floor_at(self, z: float) -> str:
        """The highest floor at or below height ``z`` (the lowest floor if none is)."""
        below = [(h, name) for name, h in self._floors.items() if h <= z + _EPS]
        if not below:
            return min(self._floors, key=self._floors.__getitem__)
        return max(below)[1]

    def platform_pose(self, floor: str, z_offset: float = 0.0) -> Pose:
        """The platform's centre at ``floor``, raised by ``z_offset`` (e.g. a robot's height)."""
        pose = self.get_pose()
        pose.position[2] = self.floor_height(floor) + z_offset
        return pose

    def landing_pose(self, floor: str, z_offset: float = 0.0) -> Pose:
        """Where robots wait for the lift and leave it to at ``floor`` (world frame)."""
        offset = self._params.landings.get(floor, self._params.landing_offset)
        assert offset is not None
        base = self.platform_pose(floor, z_offset)
        return base.compose(Pose([offset[0], offset[1], 0.0]))

    # ----- commands -----------------------------------------------------------------------

    def request_floor(self, floor_name: str) -> ElevatorRequestResult:
        """Ask the lift to go to ``floor_name`` (fire and forget, under ``request_policy``).

        Raises:
            ValueError: for an unknown floor, naming the known ones.
        """
        self._check_floor(floor_name, "request_floor")
        busy = self._state is ElevatorState.MOVING or bool(self.pending_floors)
        if not busy:
            if self.is_at(floor_name):
                return ElevatorRequestResult.REJECTED
            self.queue_trip(floor_name)
            return ElevatorRequestResult.ACCEPTED
        heading = self._pending[-1].floor if self._pending else self._target
        policy = self.request_policy
        if floor_name == heading or policy is ElevatorRequestPolicy.REJECT:
            return ElevatorRequestResult.REJECTED
        if policy is ElevatorRequestPolicy.REPLACE_NEXT:
            replaced = bool(self._pending)
            for trip in list(self._pending):
                trip.cancel()
            self._pending.clear()
            self.queue_trip(floor_name)
            return ElevatorRequestResult.REPLACED if replaced else ElevatorRequestResult.QUEUED
        self.queue_trip(floor_name)
        return ElevatorRequestResult.QUEUED

    def queue_trip(self, floor: str) -> ElevatorTrip:
        """Queue a trip to ``floor`` whatever the policy, and return it (no mission needed).

        Raises:
            ValueError: for an unknown floor.
        """
        self._check_floor(floor, "queue_trip")
        trip = ElevatorTrip(floor=floor)
        self.add_action(trip)
        self._pending.append(trip)
        return trip

    def go_to(self, floor: str) -> Any:
        """Queue a trip to ``floor`` and return the event to ``await`` (ends on arrival).

        Raises:
            ValueError: for an unknown floor.
        """
        self._check_floor(floor, "go_to")
        trip = ElevatorTrip(floor=floor)
        event = self.submit(trip)
        self._pending.append(trip)
        return event

    def ride(self, robot: Agent, floor: str, **options: Any) -> Any:
        """``await elevator.ride(robot, floor)``: hold the lift, call it to the robot's floor,
        board, travel, alight; see ``fleet_async.tasks.devices.ride`` for the options."""
        self._check_floor(floor, "ride")
        return mission_hook("elevator.ride")(self, robot, floor, **options)

    # ----- the trip (called by ElevatorTrip and the device motion system) -----------------

    def depart(self, floor: str) -> bool:
        """Start a trip to ``floor``; True if the lift already is there."""
        self._pending = [t for t in self._pending if t.status is ActionStatus.NOT_STARTED]
        z0, z1 = self.height, self._floors[floor]
        self._target = floor
        if abs(z1 - z0) <= _EPS:
            self._arrive()
            return True
        self._passengers = self.objects_on_platform()
        world = self._require_sim("depart").world
        for obj in self._passengers:
            # The world's attach, not attach_object: a lift carries what stands on it,
            # pickable or not.
            world.attach(self, obj, -1, None, True)
        self._set_state(ElevatorState.MOVING)
        self.emit(
            DeviceEvents.ELEVATOR_DEPARTED,
            elevator=self,
            floor=self._current,
            target_floor=floor,
            passengers=tuple(self._passengers),
        )
        return self.device_motion.start(self, z0, z1, abs(z1 - z0) / self.speed)

    def apply_motion(self, s: float) -> None:
        """Put the platform's top at height ``s``."""
        pose = self.get_pose()
        pose.position[2] = s
        self.set_pose(pose)

    def motion_finished(self) -> None:
        """Arrived at the target floor."""
        self._arrive()

    def halted(self) -> None:
        """The trip was cancelled: stop between floors and release the passengers."""
        self._release()
        self._target = self._current
        self._set_state(ElevatorState.IDLE)

    def update(self, dt: float) -> None:
        """ARRIVED turns IDLE one step after the arrival."""
        sim = self.sim_core
        arrived = self._state is ElevatorState.ARRIVED
        if arrived and sim is not None and sim.step_count > self._arrived_step:
            self._set_state(ElevatorState.IDLE)

    def objects_on_platform(self) -> list[SimObject]:
        """Objects standing on the platform: base within its footprint, between its top and
        ``cabin_height`` above, not carried by anything, not static scenery, not devices."""
        sim = self._require_sim("objects_on_platform")
        objects = [obj for obj in sim.sim_objects if not isinstance(obj, Device)]
        if not objects:
            return []
        # One numpy pass over every object's base; the other checks only for those inside.
        positions, _ = sim.get_poses([obj.object_id for obj in objects])
        here = self.get_pose()
        rotation = np.asarray(quat_to_rot_matrix(here.orientation)).reshape(3, 3)
        rel = (positions - here.position) @ rotation  # rows R^T v: in the platform frame
        sx, sy = self._params.platform_size
        inside = (
            (np.abs(rel[:, 0]) <= sx / 2 + _EPS)
            & (np.abs(rel[:, 1]) <= sy / 2 + _EPS)
            & (rel[:, 2] >= -0.05)
            & (rel[:, 2] <= self._params.cabin_height)
        )
        return [
            objects[i]
            for i in np.flatnonzero(inside).tolist()
            if objects[i].collision_mode is not CollisionMode.STATIC
            and not objects[i].is_attached()
        ]

    def _arrive(self) -> None:
        released = self._release()
        self._current = self._target
        sim = self.sim_core
        self._arrived_step = -1 if sim is None else sim.step_count
        self._set_state(ElevatorState.ARRIVED)
        self.emit(
            DeviceEvents.ELEVATOR_ARRIVED, elevator=self, floor=self._current, passengers=released
        )

    def _release(self) -> tuple[SimObject, ...]:
        released = tuple(self._passengers)
        for obj in released:
            if obj.sim_core is not None and obj.get_attached_parent() is self:
                self.detach_object(obj)
        self._passengers = []
        return released

    def _set_state(self, state: ElevatorState) -> None:
        previous, self._state = self._state, state
        if state is not previous:
            self.emit(
                DeviceEvents.ELEVATOR_STATE_CHANGED,
                elevator=self,
                state=state,
                previous=previous,
                floor=self._current,
                target_floor=self._target,
            )

    def _check_floor(self, floor: str, what: str) -> None:
        if floor not in self._floors:
            raise ValueError(
                f"{self.name or 'elevator'}.{what}: unknown floor {floor!r}; floors: "
                f"{list(self._floors)}"
            )
