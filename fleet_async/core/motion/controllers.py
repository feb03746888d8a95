"""Movement controllers: parameters, the built-in kinds, and building a chain from config.

An agent has a *chain* of controllers. Index 0 is the *base* controller, a
:class:`KinematicController` that turns goals and paths into motion: :class:`OmniController`
or :class:`DifferentialController`. Built-in base controllers do not run per agent: the
simulation's kinematic engine advances every agent on them in one numpy pass. Entries after the
base are *high-level* controllers (:class:`PatrolController`, :class:`RandomWalkController`,
or a user's :class:`Controller` subclass) whose ``compute(agent, dt)`` runs every step and
steers the agent through its public API (``set_path``, ``set_goal_pose``...).

A user's KinematicController subclass that overrides ``compute`` replaces the engine for its
agent and runs per agent; one that only changes parameters stays vectorised.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from fleet_async.core.base.attr_state import AttributeState
from fleet_async.core.base.config_utils import resolve_class
from fleet_async.core.base.types import MotionMode, MovementDirection, coerce_enum
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.pose_config import pose_from_config
from fleet_async.core.motion.kinematics import KIND_DIFFERENTIAL, KIND_OMNI, KinematicEngine
from fleet_async.core.motion.segments import MotionLimits, checked_limit

if TYPE_CHECKING:
    from fleet_async.core.motion.host import ControlledAgent

__all__ = [
    "CONTROLLER_REGISTRY",
    "Controller",
    "ControllerParams",
    "DifferentialController",
    "GoalController",
    "KinematicController",
    "OmniController",
    "PatrolController",
    "RandomWalkController",
    "controller_class",
    "create_controller",
    "params_dict",
    "register_controller",
]

logger = logging.getLogger(__name__)


@dataclass
class ControllerParams:
    """Kinematic limits and defaults shared by the built-in controllers.

    Each limit is a scalar (a bound on the Euclidean magnitude) or per-axis ``[x, y, z]``
    (linear: world axes; angular: roll, pitch, yaw rates).

    Attributes:
        max_linear_vel: m/s.
        max_linear_accel: m/s^2.
        max_angular_vel: rad/s.
        max_angular_accel: rad/s^2.
        default_direction: Differential travel direction when ``set_path`` gets none.
    """

    max_linear_vel: float | tuple[float, float, float] = 2.0
    max_linear_accel: float | tuple[float, float, float] = 5.0
    max_angular_vel: float | tuple[float, float, float] = 3.0
    max_angular_accel: float | tuple[float, float, float] = 10.0
    default_direction: MovementDirection = MovementDirection.FORWARD

    def __post_init__(self) -> None:
        for name in ("max_linear_vel", "max_linear_accel", "max_angular_vel", "max_angular_accel"):
            setattr(self, name, checked_limit(getattr(self, name), f"ControllerParams.{name}"))
        self.default_direction = coerce_enum(
            MovementDirection, self.default_direction, "ControllerParams.default_direction"
        )

    def limits(self) -> MotionLimits:
        """The limits as the kinematic engine takes them."""
        return MotionLimits(
            self.max_linear_vel, self.max_linear_accel, self.max_angular_vel, self.max_angular_accel
        )

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Names of the fields (to split a config dict into params and extras)."""
        names = _FIELD_NAMES.get(cls)
        if names is None:
            names = _FIELD_NAMES[cls] = tuple(f.name for f in fields(cls))
        return names


_FIELD_NAMES: dict[type, tuple[str, ...]] = {}  # a dataclass's fields never change


class Controller(AttributeState):
    """Base class of every controller.

    Subclass it for high-level behaviour and override :meth:`compute`, which the simulation
    calls once per step with the agent this controller is installed on.
    """

    def __init__(self, params: ControllerParams | None = None) -> None:
        self.params = params if params is not None else ControllerParams()

    def on_install(self, agent: ControlledAgent) -> None:
        """Called when the controller joins ``agent``'s chain."""

    def on_remove(self, agent: ControlledAgent) -> None:
        """Called when the controller leaves ``agent``'s chain."""

    def compute(self, agent: ControlledAgent, dt: float) -> None:
        """Advance this controller for one step of ``dt`` seconds."""

    def wake_time(self) -> float | None:
        """When this controller next needs :meth:`compute`, for controllers that act only on
        a free agent.

        A controller that returns a number promises that ``compute`` changes nothing while
        its agent is moving or while ``sim_time + 1e-9 < wake_time()``; the fleet then calls
        it only at steps where neither holds (``-inf``: as soon as the agent is free;
        ``inf``: never again). None (the default): call ``compute`` every step.
        """
        return None

    @property
    def is_base(self) -> bool:
        """Whether this controller moves the agent (index 0 of the chain)."""
        return isinstance(self, KinematicController)


class KinematicController(Controller):
    """A base controller; built-in subclasses are advanced by the vectorised engine.

    Args:
        params: Limits; keyword overrides (``max_linear_vel=...``) are applied on top.
    """

    kind: ClassVar[int] = KIND_OMNI
    motion_mode: ClassVar[MotionMode] = MotionMode.OMNIDIRECTIONAL

    def __init__(self, params: ControllerParams | None = None, **overrides: Any) -> None:
        base = params if params is not None else ControllerParams()
        if overrides:
            unknown = sorted(set(overrides) - set(ControllerParams.field_names()))
            if unknown:
                raise ValueError(
                    f"{type(self).__name__}: unknown parameter(s) {unknown}; "
                    f"valid: {list(ControllerParams.field_names())}"
                )
            base = ControllerParams(**{**params_dict(base), **overrides})
        super().__init__(base)

    @property
    def vectorized(self) -> bool:
        """Whether the engine advances this controller (True unless ``compute`` is overridden)."""
        return type(self).compute is KinematicController.compute

    # The motion interface an Agent delegates to. The built-in versions drive the agent's
    # slot in the simulation's kinematic engine; a custom base controller that overrides
    # ``compute`` overrides these too and calls ``agent.report_motion_end`` when it stops.

    def set_path(
        self,
        agent: ControlledAgent,
        waypoints: list[Pose],
        direction: MovementDirection,
        final_orientation_align: bool,
    ) -> None:
        """Start following ``waypoints``."""
        _engine(agent).set_path(agent.motion_slot, waypoints, direction, final_orientation_align)

    def set_velocity(
        self, agent: ControlledAgent, command: tuple[float, float, float, float]
    ) -> None:
        """Follow a body-frame (vx, vy, vz, wz) command."""
        _engine(agent).set_velocity(agent.motion_slot, command)

    def stop(self, agent: ControlledAgent) -> None:
        """Stop at once."""
        _engine(agent).stop(agent.motion_slot)

    def is_moving(self, agent: ControlledAgent) -> bool:
        """Whether the agent is moving under this controller."""
        return _engine(agent).is_moving(agent.motion_slot)

    def goal_pose(self, agent: ControlledAgent) -> Pose | None:
        """Final pose of the current path, or None."""
        return _engine(agent).goal(agent.motion_slot)

    def remaining_path(self, agent: ControlledAgent) -> list[Pose]:
        """Waypoints not reached yet."""
        return _engine(agent).remaining_waypoints(agent.motion_slot)

    def waypoint_index(self, agent: ControlledAgent) -> int:
        """Index of the waypoint being approached."""
        return _engine(agent).waypoint_index(agent.motion_slot)


def _engine(agent: ControlledAgent) -> KinematicEngine:
    engine = agent.motion_engine
    assert engine is not None
    assert agent.motion_slot >= 0
    return engine


class OmniController(KinematicController):
    """Holonomic base: translates straight to each waypoint while turning to its orientation."""

    kind = KIND_OMNI
    motion_mode = MotionMode.OMNIDIRECTIONAL


class DifferentialController(KinematicController):
    """Differential base: turns to face each waypoint, then drives straight to it.

    Args:
        params: Limits.
        wheel_separation: Track width in metres (informational; kinematics are unicycle).
        **overrides: ControllerParams fields.
    """

    kind = KIND_DIFFERENTIAL
    motion_mode = MotionMode.DIFFERENTIAL

    def __init__(
        self,
        params: ControllerParams | None = None,
        wheel_separation: float = 0.3,
        **overrides: Any,
    ):
        super().__init__(params, **overrides)
        if not wheel_separation > 0:
            raise ValueError(
                f"DifferentialController.wheel_separation: expected > 0, got {wheel_separation!r}"
            )
        self.wheel_separation = float(wheel_separation)


def params_dict(params: ControllerParams) -> dict[str, Any]:
    """The params' fields as a mapping (for building params with some fields replaced)."""
    return {name: getattr(params, name) for name in ControllerParams.field_names()}


class GoalController(Controller):
    """A high-level controller that sends its agent one goal at a time (patrol, random walk).

    Once the agent is free (not moving, no action running), :meth:`next_goal` decides and
    :meth:`send` sends. The built-in patrols and random walks due in one step start together
    (``ControllerSchedule``: the bits of this :meth:`compute`); a subclass overriding these
    methods or ``wake_time``, or an agent class overriding its motion commands, runs alone.
    """

    def compute(self, agent: ControlledAgent, dt: float) -> None:
        """Send the next goal, if any, once the agent is free."""
        if not self.ready() or agent.is_moving or agent.get_current_action() is not None:
            return
        goal = self.next_goal(agent, 0.0 if agent.sim_core is None else agent.sim_core.sim_time)
        if goal is not None:
            self.send(agent, goal)

    def send(self, agent: ControlledAgent, goal: Pose) -> None:
        """Send ``goal``: ``agent.set_path([goal])``."""
        agent.set_path([goal])

    def ready(self) -> bool:
        """Whether the controller may still send goals (checked before the agent's state)."""
        return True

    def next_goal(self, agent: ControlledAgent, now: float) -> Pose | None:
        """The goal to send now (the agent is free at sim time ``now``), or None to wait."""
        raise NotImplementedError


class PatrolController(GoalController):
    """Visit waypoints in order, pausing ``wait`` seconds at each; repeat if ``loop``.

    Args:
        waypoints: Poses or [x, y, z] positions to visit.
        wait: Sim seconds to pause at each waypoint (from the step it arrives in).
        loop: Start over after the last waypoint.
        wait_time: The incumbent's name for ``wait`` (its configs say ``wait_time``); give one
            of the two.
    """

    def __init__(
        self,
        waypoints: Sequence[Any],
        wait: float = 0.0,
        loop: bool = True,
        params: ControllerParams | None = None,
        wait_time: float | None = None,
    ):
        super().__init__(params)
        if wait_time is not None:
            if wait != 0.0:
                raise ValueError(
                    f"PatrolController: give either wait ({wait!r}) or wait_time "
                    f"({wait_time!r}), not both"
                )
            wait = wait_time
        if not waypoints:
            raise ValueError("PatrolController.waypoints: expected at least one waypoint, got []")
        self.waypoints: list[Pose] = [
            pose_from_config(w, field_name=f"PatrolController.waypoints[{i}]")
            for i, w in enumerate(waypoints)
        ]
        if not (isinstance(wait, (int, float)) and wait >= 0):
            raise ValueError(f"PatrolController.wait: expected a number >= 0 (s), got {wait!r}")
        self.wait = float(wait)
        self.loop = bool(loop)
        self.index = 0
        self.finished = False
        self._waiting_until: float | None = None
        self._sent = False

    def wake_time(self) -> float | None:
        """-inf once the agent has arrived or before the first waypoint, the end of the pause
        while pausing, inf when finished (see :meth:`Controller.wake_time`)."""
        if self.finished:
            return math.inf
        if self._sent or self._waiting_until is None:
            return -math.inf
        return self._waiting_until

    def ready(self) -> bool:
        """Until a patrol without ``loop`` has visited its last waypoint."""
        return not self.finished

    def next_goal(self, agent: ControlledAgent, now: float) -> Pose | None:
        """The next waypoint once the agent has arrived and waited."""
        if self._sent:  # just arrived at waypoints[index]
            self._sent = False
            self.index += 1
            if self.index >= len(self.waypoints):
                if not self.loop:
                    self.finished = True
                    return None
                self.index = 0
            self._waiting_until = now + self.wait
        if self._waiting_until is not None and now + 1e-9 < self._waiting_until:
            return None
        self._waiting_until = None
        self._sent = True
        return self.waypoints[self.index]


class RandomWalkController(GoalController):
    """Wander to random points within ``radius`` of ``center``, pausing between moves.

    The random stream is derived from the simulation seed and the agent's object id, so a walk
    is the same run after run whatever else is spawned around it.

    Args:
        radius: Metres around the center.
        wait_range: (min, max) sim seconds to pause after each move.
        center: [x, y, z]; defaults to the agent's pose when installed.
    """

    def __init__(
        self,
        radius: float = 5.0,
        wait_range: Sequence[float] = (0.0, 2.0),
        center: Sequence[float] | None = None,
        params: ControllerParams | None = None,
    ):
        super().__init__(params)
        if not (isinstance(radius, (int, float)) and radius > 0):
            raise ValueError(
                f"RandomWalkController.radius: expected a number > 0 (m), got {radius!r}"
            )
        lo, hi = (float(v) for v in wait_range)
        if not 0 <= lo <= hi:
            raise ValueError(
                f"RandomWalkController.wait_range: expected 0 <= min <= max, got {wait_range!r}"
            )
        self.radius = float(radius)
        self.wait_range = (lo, hi)
        self.center = None if center is None else np.asarray(center, dtype=float)
        self._rng: np.random.Generator | None = None
        self._waiting_until: float | None = None
        self._moved = False

    def on_install(self, agent: ControlledAgent) -> None:
        """Take the agent's stream (``sim.rng_for(agent, 0x5A17)``) and fix the center."""
        key = (max(agent.object_id, 0), 0x5A17)  # the stream of this agent's walk
        host = agent.sim_core
        self._rng = np.random.default_rng([0, *key]) if host is None else host.rng_for(*key)
        if self.center is None:
            self.center = agent.get_pose().position.copy()

    def wake_time(self) -> float | None:
        """-inf after a move or before the first, the end of the pause while pausing (see
        :meth:`Controller.wake_time`)."""
        if self._rng is None:
            return None
        if self._moved or self._waiting_until is None:
            return -math.inf
        return self._waiting_until

    def ready(self) -> bool:
        """Once installed (the stream is the agent's)."""
        return self._rng is not None

    def send(self, agent: ControlledAgent, goal: Pose) -> None:
        """Send ``goal``: ``agent.set_goal_pose(goal)``."""
        agent.set_goal_pose(goal)

    def next_goal(self, agent: ControlledAgent, now: float) -> Pose | None:
        """A new point once the agent has stopped and waited."""
        rng = self._rng
        assert rng is not None
        # Each draw is Generator.uniform(low, high)'s own formula, low + (high - low) * d, on
        # the stream's next double d (the same bits, a third of the call's cost).
        if self._moved:
            self._moved = False
            lo, hi = self.wait_range
            self._waiting_until = now + (lo + (hi - lo) * rng.random())
        if self._waiting_until is not None and now + 1e-9 < self._waiting_until:
            return None
        self._waiting_until = None
        assert self.center is not None
        angle = 2.0 * math.pi * rng.random()  # uniform(0, 2 pi)
        dist = self.radius * math.sqrt(rng.random())  # uniform()
        target = self.center + np.array([dist * math.cos(angle), dist * math.sin(angle), 0.0])
        target[2] = agent.get_pose().z
        self._moved = True
        return Pose(target)


CONTROLLER_REGISTRY: dict[str, type[Controller]] = {
    "omni": OmniController,
    "omnidirectional": OmniController,
    "differential": DifferentialController,
    "patrol": PatrolController,
    "random_walk": RandomWalkController,
}


def register_controller(name: str, cls: type[Controller]) -> None:
    """Make ``cls`` available as ``controller: {type: name}``.

    ``create_controller`` calls ``cls(params=ControllerParams(...), **other_keys)``, so the
    class must accept a ``params`` keyword.
    """
    if not (isinstance(cls, type) and issubclass(cls, Controller)):
        raise TypeError(f"register_controller: {cls!r} is not a Controller subclass")
    CONTROLLER_REGISTRY[name] = cls


def controller_class(spec: dict[str, Any], where: str) -> type[Controller]:
    """The controller class a ``{type|class: ...}`` mapping names.

    Raises:
        ValueError: naming ``where`` for both or neither key, or an unknown / non-Controller one.
    """
    if "type" in spec and "class" in spec:
        raise ValueError(f"{where}: give either 'type' or 'class', not both")
    if "type" not in spec and "class" not in spec:
        raise ValueError(
            f"{where}: a controller mapping needs 'type' (one of {sorted(CONTROLLER_REGISTRY)}) "
            f"or 'class' (a dotted path), got {spec!r}"
        )
    if "class" in spec:
        cls = resolve_class(str(spec["class"]))
        if not (isinstance(cls, type) and issubclass(cls, Controller)):
            raise ValueError(f"{where}.class: {spec['class']!r} is not a Controller subclass")
        return cls
    name = spec["type"]
    if name not in CONTROLLER_REGISTRY:
        raise ValueError(
            f"{where}.type: unknown controller {name!r}; known: {sorted(CONTROLLER_REGISTRY)}"
        )
    return CONTROLLER_REGISTRY[name]


def create_controller(
    spec: str | dict[str, Any], config: dict[str, Any] | None = None, *, where: str = "controller"
) -> Controller:
    """Build one controller from a registry name or a ``{type|class: ..., **params}`` mapping.

    ControllerParams fields in the mapping become the controller's params; the rest go to its
    constructor. Unknown keys are a ValueError naming them and the controller.
    """
    entry: dict[str, Any] = {"type": spec} if isinstance(spec, str) else dict(spec)
    entry.update(config or {})
    cls = controller_class(entry, where)
    kwargs = {k: v for k, v in entry.items() if k not in ("type", "class")}
    param_keys = set(ControllerParams.field_names())
    params_kw = {k: kwargs.pop(k) for k in list(kwargs) if k in param_keys}
    try:
        params = ControllerParams(**params_kw)
        return cls(params=params, **kwargs)
    except TypeError as exc:
        raise ValueError(f"{where}: bad parameters for {cls.__name__}: {exc}") from None
