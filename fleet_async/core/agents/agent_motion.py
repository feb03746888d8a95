"""An agent's controller chain and base motion (mixed into Agent).

The chain is one base controller (index 0) and any number of high-level controllers (patrol,
random walk, user code) that run per agent before it. The built-in omni and differential base
controllers are advanced for all agents at once by the simulation's kinematic engine
(``motion/kinematics.py``); a custom base controller runs per agent. Paths, velocity commands
and stops go through the base controller.
"""

from __future__ import annotations

import logging
import math
import numbers
import warnings
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from fleet_async.core.base.reprs import short_repr
from fleet_async.core.base.types import MotionMode, MovementDirection, coerce_enum
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.waypoints import Path
from fleet_async.core.motion.controllers import (
    Controller,
    ControllerParams,
    DifferentialController,
    KinematicController,
    OmniController,
    create_controller,
)

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.agents.host import AgentHost
    from fleet_async.core.motion.joints import JointSet
    from fleet_async.core.motion.kinematics import KinematicEngine
    from fleet_async.core.world.state import KinematicState

__all__ = ["AgentMotionApi"]

logger = logging.getLogger(__name__)


def _waypoints(path: Any) -> list[Pose]:
    if type(path) is list and path and all(type(w) is Pose for w in path):
        return list(path)  # the common case, checked first
    if isinstance(path, Path):
        waypoints = list(path.waypoints)
    elif isinstance(path, Pose):
        waypoints = [path]
    elif isinstance(path, (list, tuple)):
        if path and all(_is_real(v) for v in path):
            raise ValueError(
                f"set_path.path: expected a Path, a Pose or a list of Poses, got "
                f"{short_repr(path)} (numbers: for a position give Pose.from_xyz(x, y, z))"
            )
        bad = next((i for i, w in enumerate(path) if not isinstance(w, Pose)), None)
        if bad is not None:
            raise ValueError(
                f"set_path.path[{bad}]: expected a Pose, got {short_repr(path[bad])} "
                f"({type(path[bad]).__name__})"
            )
        waypoints = list(path)
    else:
        raise ValueError(
            f"set_path.path: expected a Path, a Pose or a list of Poses, got {short_repr(path)}"
        )
    if not waypoints:
        raise ValueError(
            f"set_path.path: expected at least one waypoint, got {short_repr(path)} (an empty "
            "path; stop() stops the agent)"
        )
    return waypoints


def _finite_command(vx: Any, vy: Any, vz: Any, wz: Any) -> tuple[float, float, float, float]:
    for name, value in (("vx", vx), ("vy", vy), ("vz", vz), ("wz", wz)):
        if not (_is_real(value) and math.isfinite(value)):
            raise ValueError(
                f"set_cmd_vel.{name}: expected a finite number (m/s or rad/s), got "
                f"{short_repr(value)}"
            )
    return float(vx), float(vy), float(vz), float(wz)


def _is_real(value: Any) -> bool:
    """A real number (int, float, numpy scalar), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


class AgentMotionApi:
    """The controller chain and base motion of an agent (mixed into Agent)."""

    # Provided by Agent / SimObject.
    sim_core: AgentHost | None
    check_not_removed: Callable[[str], None]  # SimObject's: raises once the agent left its sim
    use_fixed_base: bool
    motion_result: bool | None
    path_visualize: bool
    path_visualize_width: float
    _motion_mode: MotionMode
    _controllers: list[Controller]
    _slot: int
    _store: KinematicState
    _row: int
    _joint_set: JointSet | None

    @property
    def _agent(self) -> Agent:
        """This object as the Agent it is mixed into (for collaborators that take an Agent)."""
        return cast("Agent", self)

    # ----- controllers --------------------------------------------------------------------

    def _install_chain(self, chain: list[Controller]) -> None:
        old = self._controllers
        for ctrl in old:
            if not any(ctrl is c for c in chain):
                ctrl.on_remove(self._agent)
        self._release_slot()
        self._controllers = chain
        base = self.controller
        sim = self.sim_core
        if sim is not None and isinstance(base, KinematicController) and base.vectorized:
            self._slot = sim.fleet.add_slot(self._agent, base.kind)
        for ctrl in chain:
            if not old or not any(ctrl is c for c in old):
                ctrl.on_install(self._agent)
        if sim is not None:
            sim.fleet.track(self._agent)

    def _release_slot(self) -> None:
        if self._slot >= 0 and self.sim_core is not None:
            self.sim_core.fleet.remove_slot(self._slot)
        self._slot = -1

    @property
    def controller(self) -> Controller | None:
        """The base controller (index 0), or None when movement is disabled."""
        return self._controllers[0] if self._controllers else None

    @property
    def controllers(self) -> list[Controller]:
        """The whole chain, base first."""
        return list(self._controllers)

    @property
    def controller_params(self) -> ControllerParams:
        """The base controller's params (defaults when there is none)."""
        base = self.controller
        return base.params if base is not None else ControllerParams()

    @property
    def motion_engine(self) -> KinematicEngine | None:
        """The kinematic engine that holds this agent's slot (None outside a simulation)."""
        sim = self.sim_core
        return None if sim is None else sim.fleet.engine

    @property
    def motion_slot(self) -> int:
        """This agent's slot in the kinematic engine (-1 when not on a built-in controller)."""
        return self._slot

    def set_controller(self, controller: Any = None) -> None:
        """Replace the base controller (keeping high-level ones); None disables movement.

        A mapping without ``type``/``class`` keeps the current kind with new params.
        """
        rest = self._controllers[1:]
        if controller is None:
            self.stop()
            self._install_chain([])
            return
        if isinstance(controller, dict) and "type" not in controller and "class" not in controller:
            controller = {"type": self.motion_mode.value, **controller}
        ctrl = controller if isinstance(controller, Controller) else create_controller(controller)
        self.stop()
        if not ctrl.is_base:
            raise ValueError(
                f"set_controller: {type(ctrl).__name__} is not a base controller; "
                "use add_controller"
            )
        self._install_chain([ctrl, *rest])

    def add_controller(self, controller: Controller) -> None:
        """Append a high-level controller (runs before the base each step)."""
        if not isinstance(controller, Controller):
            raise TypeError(f"add_controller: expected a Controller, got {controller!r}")
        if controller.is_base:
            raise ValueError(
                f"add_controller: {type(controller).__name__} is a base controller; "
                "use set_controller"
            )
        if not self._controllers:
            raise ValueError(
                "add_controller: this agent has no base controller; set_controller first"
            )
        self._controllers.append(controller)
        controller.on_install(self._agent)
        if self.sim_core is not None:
            self.sim_core.fleet.track(self._agent)

    def remove_controller(self, controller_or_cls: Controller | type[Controller]) -> bool:
        """Remove a high-level controller by instance or class (never the base)."""
        for i, ctrl in enumerate(self._controllers[1:], start=1):
            if ctrl is controller_or_cls or (
                isinstance(controller_or_cls, type) and isinstance(ctrl, controller_or_cls)
            ):
                del self._controllers[i]
                ctrl.on_remove(self._agent)
                if self.sim_core is not None:
                    self.sim_core.fleet.track(self._agent)
                return True
        return False

    def get_controller_by_type(self, cls: type[Controller]) -> Controller | None:
        """First controller in the chain that is an instance of ``cls``."""
        return next((c for c in self._controllers if isinstance(c, cls)), None)

    @property
    def motion_mode(self) -> MotionMode:
        """OMNIDIRECTIONAL or DIFFERENTIAL (from the base controller when it is built-in)."""
        base = self.controller
        if isinstance(base, KinematicController):
            return base.motion_mode
        return self._motion_mode

    def set_motion_mode(self, mode: MotionMode | str) -> None:
        """Deprecated: swap the base for the default omni / differential controller.

        Raises:
            ValueError: while the agent is moving.
        """
        warnings.warn(
            "Agent.set_motion_mode is deprecated; "
            "use agent.set_controller('omni' | 'differential')",
            DeprecationWarning,
            stacklevel=2,
        )
        mode = coerce_enum(MotionMode, mode, "motion_mode")
        if self.is_moving:
            raise ValueError(
                "set_motion_mode: cannot change the motion mode while moving; stop() first"
            )
        cls = DifferentialController if mode is MotionMode.DIFFERENTIAL else OmniController
        self._motion_mode = mode
        self._install_chain([cls(self.controller_params), *self._controllers[1:]])

    def has_stepped_controllers(self) -> bool:
        """Whether any controller needs a per-agent ``compute`` call each step."""
        base = self.controller
        custom_base = base is not None and not (
            isinstance(base, KinematicController) and base.vectorized
        )
        return custom_base or len(self._controllers) > 1

    def step_controllers(self, dt: float) -> None:
        """High-level controllers, then a custom base controller (called by the simulation)."""
        for ctrl in self._controllers[1:]:
            ctrl.compute(self._agent, dt)
        base = self.controller
        if base is not None and not (isinstance(base, KinematicController) and base.vectorized):
            base.compute(self._agent, dt)

    # ----- motion -------------------------------------------------------------------------

    @property
    def motion_blocker(self) -> str | None:
        """Why this agent cannot move (fixed base, no base controller), or None if it can."""
        if self.use_fixed_base:
            return f"{self!r} has a fixed base"
        if not isinstance(self.controller, KinematicController):
            return f"{self!r} has no base controller (movement disabled)"
        return None

    def _base(self, what: str) -> KinematicController | None:
        self.check_not_removed(what)
        if self.use_fixed_base:
            logger.warning("%s ignored: %r has a fixed base", what, self)
            return None
        base = self.controller
        if not isinstance(base, KinematicController):
            logger.warning("%s ignored: %r has no base controller", what, self)
            return None
        if self.sim_core is None:
            raise ValueError(f"{what}: {self!r} is not part of a simulation")
        return base

    def set_path(
        self,
        path: Path | Sequence[Pose] | Pose,
        auto_approach: bool = True,
        final_orientation_align: bool = True,
        direction: MovementDirection | str | None = None,
    ) -> None:
        """Follow ``path`` (replacing any motion in progress).

        Args:
            path: Waypoints in the world frame.
            auto_approach: Drive from the current pose to the first waypoint; when False the
                first waypoint is taken as the start and skipped (unless it is the only one).
            final_orientation_align: End turned to the last waypoint's orientation.
            direction: "forward", "backward" or "auto" (differential); None uses the
                controller's ``default_direction``.

        Raises:
            ValueError: for an empty path, or an item that is not a Pose (naming its index).
        """
        waypoints = _waypoints(path)
        base = self._base("set_path")
        if base is None:
            return
        if not auto_approach and len(waypoints) > 1:
            waypoints = waypoints[1:]
        chosen = (
            base.params.default_direction
            if direction is None
            else coerce_enum(MovementDirection, direction, "set_path.direction")
        )
        self.motion_result = None
        base.set_path(self._agent, waypoints, chosen, bool(final_orientation_align))
        if self.path_visualize and self.sim_core is not None and self.sim_core.is_gui:
            Path(waypoints).visualize(
                line_width=self.path_visualize_width, physics_client_id=self.sim_core.client
            )

    def set_goal_pose(self, goal: Pose, direction: MovementDirection | str | None = None) -> None:
        """Drive to ``goal`` (a one-waypoint path)."""
        if not isinstance(goal, Pose):
            hint = (
                " (numbers: for a position give Pose.from_xyz(x, y, z))"
                if isinstance(goal, (list, tuple)) and goal and all(_is_real(v) for v in goal)
                else ""
            )
            raise ValueError(
                f"set_goal_pose.goal: expected a Pose, got {short_repr(goal)} "
                f"({type(goal).__name__}){hint}"
            )
        self.set_path([goal], direction=direction)

    def set_cmd_vel(
        self, vx: float = 0.0, vy: float = 0.0, wz: float = 0.0, vz: float = 0.0
    ) -> None:
        """Follow a body-frame velocity command (m/s, rad/s) until stopped or given a path.

        Raises:
            ValueError: for a value that is not a finite number (naming it), or a sideways
                command (``vy``) on a differential robot.
        """
        command = _finite_command(vx, vy, vz, wz)
        base = self._base("set_cmd_vel")
        if base is None:
            return
        if vy != 0.0 and base.motion_mode is MotionMode.DIFFERENTIAL:
            raise ValueError(
                f"set_cmd_vel: vy={vy!r} but a differential robot cannot move sideways"
            )
        self.motion_result = None
        base.set_velocity(self._agent, command)

    def stop(self) -> None:
        """Stop moving and forget the goal and path."""
        base = self.controller
        if isinstance(base, KinematicController) and self.sim_core is not None:
            base.stop(self._agent)

    @property
    def is_moving(self) -> bool:
        """Whether the agent follows a path or a non-zero velocity command."""
        base = self.controller
        return (
            isinstance(base, KinematicController)
            and self.sim_core is not None
            and base.is_moving(self._agent)
        )

    @property
    def velocity(self) -> np.ndarray:
        """World-frame linear velocity [vx, vy, vz] in m/s over the last step (a copy)."""
        return self._store.velocity[self._row].copy()

    def get_velocity(self) -> np.ndarray:
        """Same as :attr:`velocity`."""
        return self.velocity

    @property
    def angular_velocity(self) -> float:
        """Yaw rate in rad/s over the last step."""
        return float(self._store.angular_velocity[self._row][2])

    @property
    def goal_pose(self) -> Pose | None:
        """The final pose of the current path, or None when idle."""
        base = self.controller
        return (
            base.goal_pose(self._agent)
            if isinstance(base, KinematicController) and self.sim_core
            else None
        )

    @property
    def path(self) -> list[Pose]:
        """Waypoints not reached yet; empty when idle."""
        base = self.controller
        return (
            base.remaining_path(self._agent)
            if isinstance(base, KinematicController) and self.sim_core
            else []
        )

    @property
    def current_waypoint_index(self) -> int:
        """Index (in the path given to ``set_path``) of the waypoint being approached."""
        base = self.controller
        return (
            base.waypoint_index(self._agent)
            if isinstance(base, KinematicController) and self.sim_core
            else 0
        )

    def update(self, dt: float) -> None:
        """Advance this agent alone by ``dt`` seconds, outside the step loop.

        For a custom loop (the reference API's ``agent.update(dt)``): high-level controllers,
        the base motion toward the goal within the limits, and kinematic joints. Inside
        ``step_once`` the simulation has already moved every agent in its vectorised pass, so
        a subclass's ``update`` that calls ``super().update(dt)`` moves nothing twice. Does
        nothing on a fixed base (it has no goal) or outside a simulation. The action queue
        advances only in ``step_once``.
        """
        sim = self.sim_core
        if sim is None or sim.in_step:
            return
        if self.has_stepped_controllers():
            self.step_controllers(dt)
        if self._slot >= 0:
            sim.fleet.engine.advance_slot(self._slot, dt)
            sim.world.on_pose_written(self._agent, True)
        joints = self._joint_set
        if joints is not None and joints.kinematic and joints.moving:
            joints.advance(dt)

    def overrides_update(self) -> bool:
        """Whether a subclass overrides ``update`` (the simulation then calls it every step)."""
        return type(self).update is not AgentMotionApi.update

    def note_motion_end(self, reached: bool) -> None:
        """Record how the last motion ended (called by the simulation)."""
        self.motion_result = reached

    def report_motion_end(self, reached: bool) -> None:
        """For custom base controllers: the agent stopped (``reached``: at its goal)."""
        if self.sim_core is not None:
            self.sim_core.fleet.motion_ended(self._agent, reached)

    def _limit(self, name: str) -> np.ndarray:
        return np.broadcast_to(
            np.asarray(getattr(self.controller_params, name), dtype=float), (3,)
        ).copy()

    @property
    def max_linear_vel(self) -> np.ndarray:
        """Per-axis linear speed limit (m/s)."""
        return self._limit("max_linear_vel")

    @property
    def max_linear_accel(self) -> np.ndarray:
        """Per-axis linear acceleration limit (m/s^2)."""
        return self._limit("max_linear_accel")

    @property
    def max_angular_vel(self) -> np.ndarray:
        """Per-axis angular speed limit (rad/s)."""
        return self._limit("max_angular_vel")

    @property
    def max_angular_accel(self) -> np.ndarray:
        """Per-axis angular acceleration limit (rad/s^2)."""
        return self._limit("max_angular_accel")
