"""Door: a leaf that slides or swings open over a set time; closed, it is an obstacle.

States (``DoorState``, the reference API's enum): CLOSED -> OPENING -> OPEN -> CLOSING ->
CLOSED. Only a fully open door is OPEN; a door stopped part-way (its action cancelled) reports
CLOSED, with :attr:`Door.openness` telling how far it got. The leaf is a collision body (a box
``width`` x ``thickness`` x ``height`` by default): closed, it spans the doorway, so a robot
that drives through collides with it; open, it has slid (``sliding``) or swung (``hinged``) out
of the way.

Commands:

- ``door.open()`` / ``door.close()`` queue the motion on the door's action queue (first come,
  first served) and return the event missions ``await``; it ends when the door is fully open
  (closed), at the end of that step. Opening from closed takes ``open_time`` seconds exactly
  (``ceil(open_time / dt)`` steps), from part-way the remaining fraction of it.
- ``door.request_open()`` / ``request_close()`` (the reference API's names) act at once: they
  drop whatever the door was doing or had queued and reverse it, as a door controller would.
- ``await door.pass_through(robot, path)`` is the mission-layer composite (the doorway is a
  sim-aware Resource: one robot at a time; ``fleet_async.tasks.devices``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING, Any, ClassVar

from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.base.device_events import DeviceEvents
from fleet_async.core.base.types import DoorState, coerce_enum
from fleet_async.core.devices.device import Device
from fleet_async.core.devices.motion import DeviceAction
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.missions.hooks import mission_hook
from fleet_async.core.world.shapes import ShapeParams

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent

__all__ = ["Door", "DoorAction", "DoorParams", "DoorType"]


class DoorType(str, Enum):
    """How a door's leaf moves: along its own x axis, or about a vertical hinge."""

    SLIDING = "sliding"
    HINGED = "hinged"


def _positive(value: Any, name: str, allow_zero: bool = False) -> float:
    ok = (
        isinstance(value, (int, float))
        and not isinstance(value, bool)
        and math.isfinite(value)
        and (value >= 0 if allow_zero else value > 0)
    )
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name}: expected a finite number {bound}, got {value!r}")
    return float(value)


@dataclass
class DoorParams(AgentSpawnParams):
    """Spawn parameters of a Door (AgentSpawnParams plus the door's own fields).

    The pose is the middle of the doorway at floor level, the leaf's x axis along the doorway.
    Without ``visual_shape`` / ``collision_shape`` the leaf is a box of ``width`` x
    ``thickness`` x ``height`` standing on that point.

    Attributes:
        door_type: "sliding" (the leaf slides along its +x axis by ``open_distance``) or
            "hinged" (it swings by ``swing_angle`` about a vertical hinge at its -x edge).
        width: Leaf width along x, m.
        height: Leaf height, m.
        thickness: Leaf thickness along y, m.
        open_time: Seconds from fully closed to fully open (0: at once).
        close_time: Seconds from fully open to fully closed (default ``open_time``).
        open_distance: Sliding doors: how far the leaf slides, m; negative slides along -x
            (default ``width``).
        swing_angle: Hinged doors: opening angle, rad; its sign picks the side (default pi/2).
        initial_state: "closed" or "open".
        rgba_color: Colour of the default leaf.
    """

    use_fixed_base: bool = True
    door_type: DoorType = DoorType.SLIDING
    width: float = 1.0
    height: float = 2.0
    thickness: float = 0.05
    open_time: float = 2.0
    close_time: float | None = None
    open_distance: float | None = None
    swing_angle: float = math.pi / 2
    initial_state: DoorState = DoorState.CLOSED
    rgba_color: list[float] = field(default_factory=lambda: [0.55, 0.35, 0.2, 1.0])

    def __post_init__(self) -> None:
        super().__post_init__()
        self.door_type = coerce_enum(DoorType, self.door_type, "DoorParams.door_type")
        for name in ("width", "height", "thickness"):
            setattr(self, name, _positive(getattr(self, name), f"DoorParams.{name}"))
        self.open_time = _positive(self.open_time, "DoorParams.open_time", allow_zero=True)
        if self.close_time is not None:
            self.close_time = _positive(self.close_time, "DoorParams.close_time", allow_zero=True)
        if self.open_distance is not None and not (
            isinstance(self.open_distance, (int, float)) and math.isfinite(self.open_distance)
        ):
            raise ValueError(
                "DoorParams.open_distance: expected a finite number (m), got "
                f"{self.open_distance!r}"
            )
        if not (isinstance(self.swing_angle, (int, float)) and math.isfinite(self.swing_angle)):
            raise ValueError(
                f"DoorParams.swing_angle: expected a finite angle (rad), got {self.swing_angle!r}"
            )
        self.initial_state = coerce_enum(DoorState, self.initial_state, "DoorParams.initial_state")
        if self.initial_state not in (DoorState.CLOSED, DoorState.OPEN):
            raise ValueError(
                f"DoorParams.initial_state: expected 'closed' or 'open', got "
                f"{self.initial_state.value!r}"
            )

    @classmethod
    def from_dict(cls, config: dict[str, Any], *, source: str | None = None) -> DoorParams:
        """Build from a mapping (``pose`` + ``yaw`` accepted, as for agents)."""
        params = super().from_dict(config, source=source)
        assert isinstance(params, DoorParams)
        return params


@dataclass(eq=False)
class DoorAction(DeviceAction):
    """Open (``opening=True``) or close the door that runs it."""

    opening: bool = True

    def begin(self, agent: Agent) -> bool:
        """Start the leaf moving; True if it already was where asked."""
        if not isinstance(agent, Door):
            return self.fail(f"DoorAction runs on a Door, not {agent!r}")
        return agent.start_leaf(self.opening)

    def halt(self, agent: Agent) -> None:
        """Stopped part-way: the door holds there (and is not passable)."""
        if isinstance(agent, Door):
            agent.leaf_stopped()


class Door(Device):
    """A door device; see the module docstring for its states and commands."""

    _spawn_params_cls: ClassVar[type[AgentSpawnParams]] = DoorParams
    device_type: ClassVar[str] = "door"

    _closed_pose: Pose
    _params: DoorParams
    _openness: float = 0.0
    _state: DoorState = DoorState.CLOSED

    @classmethod
    def complete_params(cls, params: AgentSpawnParams) -> AgentSpawnParams:
        """Give a door without shapes its default box leaf."""
        assert isinstance(params, DoorParams)
        if params.visual_shape is not None or params.collision_shape is not None:
            return params
        half = [params.width / 2, params.thickness / 2, params.height / 2]
        offset = Pose([0.0, 0.0, params.height / 2])
        visual = ShapeParams("box", half_extents=half, rgba_color=list(params.rgba_color))
        collision = ShapeParams("box", half_extents=half)
        return DoorParams(
            **{
                **{f: getattr(params, f) for f in params.field_names()},
                "visual_shape": visual,
                "collision_shape": collision,
                "visual_frame_pose": params.visual_frame_pose or offset,
                "collision_frame_pose": params.collision_frame_pose or offset,
            }
        )

    def setup(self, params: AgentSpawnParams) -> None:
        """Remember the closed pose; open the leaf if the door starts open."""
        assert isinstance(params, DoorParams)
        self._params = params
        self._closed_pose = self.get_pose()
        if params.initial_state is DoorState.OPEN:
            self.apply_motion(1.0)
            self._state = DoorState.OPEN

    # ----- state --------------------------------------------------------------------------

    @property
    def door_state(self) -> DoorState:
        """CLOSED, OPENING, OPEN or CLOSING (only a fully open door is OPEN)."""
        return self._state

    @property
    def is_open(self) -> bool:
        """Whether the door is fully open (robots may pass)."""
        return self._state is DoorState.OPEN

    @property
    def openness(self) -> float:
        """How far the leaf is open: 0.0 closed, 1.0 fully open."""
        return self._openness

    @property
    def door_type(self) -> DoorType:
        """SLIDING or HINGED."""
        return self._params.door_type

    @property
    def open_time(self) -> float:
        """Seconds from fully closed to fully open."""
        return self._params.open_time

    @property
    def close_time(self) -> float:
        """Seconds from fully open to fully closed."""
        close = self._params.close_time
        return self._params.open_time if close is None else close

    @property
    def closed_pose(self) -> Pose:
        """The leaf's pose when closed (the doorway's middle at floor level)."""
        return self._closed_pose.copy()

    # ----- commands -----------------------------------------------------------------------

    def open(self, *, detached: bool = False) -> Any:
        """Queue opening; return the event to ``await`` (ends when fully open).
        ``detached``: it goes on even if the mission that asked ends first."""
        return self.submit(DoorAction(opening=True), detached=detached, what="door.open")

    def close(self, *, detached: bool = False) -> Any:
        """Queue closing; return the event to ``await`` (ends when fully closed).
        ``detached``: it goes on even if the mission that asked ends first."""
        return self.submit(DoorAction(opening=False), detached=detached, what="door.close")

    def request_open(self) -> None:
        """Open now: drop what the door was doing or had queued (no-op if open or opening)."""
        if self._state in (DoorState.CLOSED, DoorState.CLOSING):
            self.clear_actions()
            self.add_action(DoorAction(opening=True))

    def request_close(self) -> None:
        """Close now: drop what the door was doing or had queued (no-op if closed or closing)."""
        if self._state in (DoorState.OPEN, DoorState.OPENING):
            self.clear_actions()
            self.add_action(DoorAction(opening=False))

    def pass_through(self, robot: Agent, path: Any, **options: Any) -> Any:
        """``await door.pass_through(robot, path)``: take the doorway (one robot at a time),
        open, drive ``path``, and close behind if nobody waits; see
        ``fleet_async.tasks.devices.pass_through`` for the options."""
        return mission_hook("door.pass_through")(self, robot, path, **options)

    # ----- motion (called by DoorAction and the device motion system) ---------------------

    def start_leaf(self, opening: bool) -> bool:
        """Move the leaf to open (or closed); True if it already is there."""
        target = 1.0 if opening else 0.0
        seconds = self.open_time if opening else self.close_time
        if self._openness != target:
            self._set_state(DoorState.OPENING if opening else DoorState.CLOSING)
        return self.device_motion.start(
            self, self._openness, target, abs(target - self._openness) * seconds
        )

    def leaf_stopped(self) -> None:
        """The leaf was stopped part-way."""
        self._set_state(DoorState.OPEN if self._openness >= 1.0 else DoorState.CLOSED)

    def apply_motion(self, s: float) -> None:
        """Put the leaf at openness ``s``."""
        self._openness = s
        self.set_pose(self._leaf_pose(s))

    def motion_finished(self) -> None:
        """The leaf arrived: OPEN or CLOSED."""
        self._set_state(DoorState.OPEN if self._openness >= 1.0 else DoorState.CLOSED)

    def _leaf_pose(self, s: float) -> Pose:
        params = self._params
        if params.door_type is DoorType.SLIDING:
            distance = params.width if params.open_distance is None else params.open_distance
            return self._closed_pose.compose(Pose([s * distance, 0.0, 0.0]))
        half = params.width / 2
        swing = Pose.from_euler(0.0, 0.0, 0.0, yaw=s * params.swing_angle)
        about_hinge = Pose([-half, 0.0, 0.0]).compose(swing).compose(Pose([half, 0.0, 0.0]))
        return self._closed_pose.compose(about_hinge)

    def _set_state(self, state: DoorState) -> None:
        previous, self._state = self._state, state
        if state is not previous:
            self.emit(DeviceEvents.DOOR_STATE_CHANGED, door=self, state=state, previous=previous)
