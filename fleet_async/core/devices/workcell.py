"""Workcells: stations that dispense items to robots, or ingest the items robots bring.

A :class:`Workcell` is a device with a pad on the floor and its own action queue, so it serves
one robot at a time, in request order:

- ``station.dispense(robot)``: the robot must stand within ``reach`` of the station (its base,
  in the horizontal plane). After ``processing_time`` seconds the station makes a new item and
  puts it on the robot (attached at ``attach_offset``); the awaited value is the finished
  :class:`DispenseAction`, whose ``item`` is the new object.
- ``station.ingest(robot, item=None)``: the robot hands over ``item`` (default: the first
  object it carries) at once; the item lies on the station for ``processing_time`` seconds and
  is then consumed (removed from the simulation, or kept there with ``keep_ingested``).

Both return the event to ``await`` (ActionFailedError with the reason when the robot is out of
reach or carries nothing). ``request_dispense`` / ``request_ingest`` queue the same actions
without a mission. Stations are usually declared through :class:`WorkcellPlugin` (YAML
``plugins: [{type: workcell, config: {...}}]``); ``type: workcell`` entities work as well.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING, Any, ClassVar

from fleet_async.core.actions.action import Action, WaitHint
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.base.device_events import DeviceEvents
from fleet_async.core.base.types import CollisionMode, coerce_enum
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.devices.device import Device
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.pose_config import pose_from_config
from fleet_async.core.world.shapes import ShapeParams

if TYPE_CHECKING:
    from fleet_async.core.actions.host import ActingAgent
    from fleet_async.core.agents.agent import Agent

__all__ = ["DispenseAction", "IngestAction", "Workcell", "WorkcellKind", "WorkcellParams"]

_EPS = 1e-9
_PAD_COLORS = {"dispenser": [0.2, 0.7, 0.3, 1.0], "ingestor": [0.8, 0.25, 0.2, 1.0]}


def _label(obj: Any) -> str:
    """An object's name, or its repr when it has none (for messages)."""
    return str(obj.name) if getattr(obj, "name", None) else repr(obj)


class WorkcellKind(str, Enum):
    """What a workcell does."""

    DISPENSER = "dispenser"
    INGESTOR = "ingestor"


def _offset_pose(value: Any, name: str) -> Pose:
    """``[x, y, z]`` or ``[x, y, z, roll, pitch, yaw]`` (m, rad) as a Pose."""
    if isinstance(value, Pose):
        return value
    if isinstance(value, (list, tuple)) and len(value) == 6:
        return Pose.from_euler(*value)
    return pose_from_config(value, field_name=name)


@dataclass
class WorkcellParams(AgentSpawnParams):
    """Spawn parameters of a Workcell.

    The pose is the middle of the station's pad on the floor. Without shapes, the pad is a flat
    box of ``pad_size`` (green for dispensers, red for ingestors) that robots drive over (no
    collision).

    Attributes:
        kind: "dispenser" or "ingestor".
        processing_time: Seconds per item (>= 0).
        reach: How far (m, horizontal) a robot's base may stand from the station.
        item_shape: Shape of dispensed items (a box of 0.1 m half extents by default).
        item_mass: Mass of dispensed items, kg (0: kinematic).
        attach_offset: Item pose on the robot: [x, y, z] or [x, y, z, roll, pitch, yaw].
        item_offset: Where items lie on the station, relative to its pose.
        keep_ingested: Keep ingested items on the station instead of removing them.
        pad_size: [x, y] of the default pad, m.
    """

    use_fixed_base: bool = True
    collision_mode: CollisionMode = CollisionMode.DISABLED
    kind: WorkcellKind = WorkcellKind.DISPENSER
    processing_time: float = 1.0
    reach: float = 1.0
    item_shape: ShapeParams | None = None
    item_mass: float = 0.0
    attach_offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.2])
    item_offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.1])
    keep_ingested: bool = False
    pad_size: list[float] = field(default_factory=lambda: [0.6, 0.6])

    def __post_init__(self) -> None:
        super().__post_init__()
        self.kind = coerce_enum(WorkcellKind, self.kind, "WorkcellParams.kind")
        for name in ("processing_time", "reach", "item_mass"):
            value = getattr(self, name)
            if not (
                isinstance(value, (int, float))
                and not isinstance(value, bool)
                and math.isfinite(value)
                and value >= 0
            ):
                raise ValueError(
                    f"WorkcellParams.{name}: expected a finite number >= 0, got {value!r}"
                )
            setattr(self, name, float(value))
        if isinstance(self.item_shape, dict):
            self.item_shape = ShapeParams.from_dict(self.item_shape)
        if self.item_shape is None:
            self.item_shape = ShapeParams(
                "box", half_extents=[0.1, 0.1, 0.1], rgba_color=[0.9, 0.6, 0.1, 1.0]
            )
        for name in ("attach_offset", "item_offset"):
            _offset_pose(getattr(self, name), f"WorkcellParams.{name}")  # validate early

    @classmethod
    def from_dict(cls, config: dict[str, Any], *, source: str | None = None) -> WorkcellParams:
        """Build from a mapping (``pose`` + ``yaw`` accepted, as for agents)."""
        params = super().from_dict(config, source=source)
        assert isinstance(params, WorkcellParams)
        return params


@dataclass(eq=False)
class _StationAction(Action):
    """An item hand-over run by the station's queue: a check, a timer, a completion."""

    robot: Any = None
    item: SimObject | None = None
    _until: float | None = field(default=None, init=False, repr=False)

    def execute(self, agent: ActingAgent, dt: float) -> bool:
        """Start (checks, hand-over) on the first call; finish when the timer runs out."""
        if not isinstance(agent, Workcell):
            return self.fail(f"{type(self).__name__} runs on a Workcell, not {agent!r}")
        sim = agent.sim_core
        now = 0.0 if sim is None else sim.action_time
        if self._until is None:
            problem = agent.reach_problem(self.robot) or self.start(agent)
            if problem:
                return self.fail(problem)
            self._until = now + agent.processing_time
        if now + _EPS < self._until:
            return False
        self.finish(agent)
        return True

    def start(self, station: Workcell) -> str | None:
        """Begin; return why it cannot, or None (subclasses)."""
        return None

    def finish(self, station: Workcell) -> None:
        """The processing time is over (subclasses)."""

    def wait_hint(self) -> WaitHint:
        """Waits for the processing time to run out."""
        return ("time", self._until)

    def reset(self) -> None:
        """Forget progress."""
        self._reset_status()
        self._until = None


@dataclass(eq=False)
class DispenseAction(_StationAction):
    """Give ``robot`` a new item after the processing time; ``item`` is set when done."""

    def finish(self, station: Workcell) -> None:
        """Make the item and put it on the robot."""
        self.item = station.hand_over_new_item(self.robot)


@dataclass(eq=False)
class IngestAction(_StationAction):
    """Take ``item`` (default: the first thing ``robot`` carries) and consume it."""

    def start(self, station: Workcell) -> str | None:
        """Take the item off the robot now."""
        robot: Agent = self.robot
        if self.item is None:
            carried = robot.get_attached_objects()
            if not carried:
                return f"{_label(robot)} carries nothing to ingest"
            self.item = carried[0]
        if self.item.get_attached_parent() is not robot:
            return f"{_label(robot)} does not carry {self.item!r}"
        robot.detach_object(self.item, drop_pose=station.item_pose())
        return None

    def finish(self, station: Workcell) -> None:
        """Consume the item."""
        assert self.item is not None
        station.consume(self.robot, self.item)


class Workcell(Device):
    """A dispenser or ingestor station; see the module docstring."""

    _spawn_params_cls: ClassVar[type[AgentSpawnParams]] = WorkcellParams
    device_type: ClassVar[str] = "workcell"

    _params: WorkcellParams

    @classmethod
    def complete_params(cls, params: AgentSpawnParams) -> AgentSpawnParams:
        """Give a station without shapes its pad."""
        assert isinstance(params, WorkcellParams)
        if params.visual_shape is not None or params.collision_shape is not None:
            return params
        sx, sy = (float(v) for v in params.pad_size)
        pad = ShapeParams(
            "box", half_extents=[sx / 2, sy / 2, 0.005], rgba_color=_PAD_COLORS[params.kind.value]
        )
        fields = {f: getattr(params, f) for f in params.field_names()}
        return WorkcellParams(**{**fields, "visual_shape": pad})

    def setup(self, params: AgentSpawnParams) -> None:
        """Read the station's fields."""
        assert isinstance(params, WorkcellParams)
        self._params = params
        self._attach = _offset_pose(params.attach_offset, "WorkcellParams.attach_offset")
        self._item_offset = _offset_pose(params.item_offset, "WorkcellParams.item_offset")
        self.dispensed: list[SimObject] = []
        """Items this station made, in order."""
        self.ingested: list[SimObject] = []
        """Items this station consumed, in order (removed ones are no longer in the sim)."""

    @property
    def kind(self) -> WorkcellKind:
        """DISPENSER or INGESTOR."""
        return self._params.kind

    @property
    def processing_time(self) -> float:
        """Seconds per item."""
        return self._params.processing_time

    @property
    def reach(self) -> float:
        """How far (m, horizontal) a robot may stand from the station."""
        return self._params.reach

    # ----- commands -----------------------------------------------------------------------

    def dispense(self, robot: Agent) -> Any:
        """Queue a dispense for ``robot``; return the event to ``await`` (a DispenseAction)."""
        return self.submit(self._dispense_action(robot))

    def ingest(self, robot: Agent, item: SimObject | None = None) -> Any:
        """Queue an ingest from ``robot``; return the event to ``await`` (an IngestAction)."""
        return self.submit(self._ingest_action(robot, item))

    def request_dispense(self, robot: Agent) -> DispenseAction:
        """Queue a dispense without a mission; return the action."""
        action = self._dispense_action(robot)
        self.add_action(action)
        return action

    def request_ingest(self, robot: Agent, item: SimObject | None = None) -> IngestAction:
        """Queue an ingest without a mission; return the action."""
        action = self._ingest_action(robot, item)
        self.add_action(action)
        return action

    # ----- what the actions call -----------------------------------------------------------

    def reach_problem(self, robot: Agent) -> str | None:
        """Why ``robot`` cannot be served from where it stands, or None."""
        here, there = self.get_pose().position, robot.get_pose().position
        distance = math.hypot(float(there[0] - here[0]), float(there[1] - here[1]))
        if distance > self.reach + _EPS:
            return (
                f"{_label(robot)} is {distance:.2f} m from {_label(self)} (reach {self.reach:g} m)"
            )
        return None

    def item_pose(self) -> Pose:
        """Where an item lies on the station (world frame)."""
        return self.get_pose().compose(self._item_offset)

    def hand_over_new_item(self, robot: Agent) -> SimObject:
        """Make an item on the station and attach it to ``robot``."""
        sim = self._require_sim("dispense")
        shape = self._params.item_shape
        assert shape is not None
        item = SimObject.from_params(
            SimObjectSpawnParams(
                visual_shape=shape,
                collision_shape=shape,
                initial_pose=self.item_pose(),
                mass=self._params.item_mass,
                name=f"{self.name or 'workcell'}_item{len(self.dispensed)}",
            ),
            sim,
        )
        robot.attach_object(item, relative_pose=self._attach)
        self.dispensed.append(item)
        self.emit(DeviceEvents.WORKCELL_DISPENSED, workcell=self, robot=robot, item=item)
        return item

    def consume(self, robot: Agent, item: SimObject) -> None:
        """Consume an item that lay on the station."""
        self.ingested.append(item)
        if not self._params.keep_ingested and item.sim_core is not None:
            item.sim_core.remove_object(item)
        self.emit(DeviceEvents.WORKCELL_INGESTED, workcell=self, robot=robot, item=item)

    def _dispense_action(self, robot: Agent) -> DispenseAction:
        if self.kind is not WorkcellKind.DISPENSER:
            raise ValueError(f"{_label(self)} is an ingestor; it cannot dispense")
        return DispenseAction(robot=robot)

    def _ingest_action(self, robot: Agent, item: SimObject | None) -> IngestAction:
        if self.kind is not WorkcellKind.INGESTOR:
            raise ValueError(f"{_label(self)} is a dispenser; it cannot ingest")
        return IngestAction(robot=robot, item=item)
