"""Agent: a SimObject that moves under a controller chain and runs an action queue.

Motion is delegated to the base controller (index 0 of the chain); the built-in omni and
differential controllers are advanced for all agents at once by the simulation's kinematic
engine (``core/kinematics.py``), so an Agent's own per-step Python cost is zero unless it
has high-level controllers or plugins. Actions go through the simulation's event-driven
queue (``core/action_queue.py``).
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
import pybullet as p

from fleet_async.core.actions.action import Action
from fleet_async.core.agents.agent_joints import AgentJointsApi
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.agents.agent_plugins import AgentPlugin, BatteryPlugin, create_agent_plugin
from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.types import CollisionMode, MotionMode, MovementDirection, coerce_enum
from fleet_async.core.bodies.models import resolve_model
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.bodies.spawning import create_bodies, create_body, wrap_all
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.waypoints import Path
from fleet_async.core.missions.agent_missions import AgentMissionApi
from fleet_async.core.motion.controllers import (
    Controller,
    ControllerParams,
    DifferentialController,
    KinematicController,
    OmniController,
    build_controller_chain,
    create_controller,
)
from fleet_async.core.motion.ik import IKParams
from fleet_async.core.motion.joints import JointSet

if TYPE_CHECKING:
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["Agent", "AgentSpawnParams", "IKParams"]

logger = logging.getLogger(__name__)


def _waypoints(path: Any) -> list[Pose]:
    if isinstance(path, Path):
        return list(path.waypoints)
    if isinstance(path, Pose):
        return [path]
    if isinstance(path, (list, tuple)):
        bad = next((i for i, w in enumerate(path) if not isinstance(w, Pose)), None)
        if bad is None:
            return list(path)
        raise ValueError(f"set_path: waypoint {bad} is not a Pose: {path[bad]!r}")
    raise ValueError(f"set_path: expected a Path, a Pose or a list of Poses, got {path!r}")


def _construct_or_remove_body(
    cls: type[Agent], sim_core: MultiRobotSimulationCore | None, body: int, **kwargs: Any
) -> Agent:
    """Build the agent around a body this module created; remove the body if that fails."""
    try:
        return cls(body, sim_core=sim_core, **kwargs)
    except Exception:
        p.removeBody(body, physicsClientId=0 if sim_core is None else sim_core.client)
        raise


def _mesh_kwargs(spawn_params: AgentSpawnParams) -> dict[str, Any]:
    """Agent constructor arguments for a shape-based or virtual agent."""
    virtual = spawn_params.kind == "virtual"
    return {
        "motion_mode": spawn_params.motion_mode,
        "use_fixed_base": spawn_params.use_fixed_base,
        "collision_mode": CollisionMode.DISABLED if virtual else spawn_params.collision_mode,
        "name": spawn_params.name,
        "user_data": dict(spawn_params.user_data),
        "mass": spawn_params.mass,
        "ik_params": spawn_params.ik_params,
        "controller": spawn_params.controller,
        "notify_spawn": False,
    }


class Agent(AgentMissionApi, AgentJointsApi, SimObject):
    """A robot: mobile (omni / differential) or fixed-base, mesh, URDF or virtual.

    Args:
        body_id: PyBullet body id.
        urdf_path: The URDF it was loaded from, if any.
        motion_mode: Default base controller when ``controller`` names none (deprecated
            shortcut; prefer ``controller="omni"`` / ``"differential"``).
        use_fixed_base: The base never moves; motion commands are ignored with a warning.
        collision_mode: Collision participation.
        sim_core: The simulation.
        name: Human-readable name.
        user_data: Free-form metadata.
        mass: kg; None reads PyBullet's.
        ik_params: IK settings (arms).
        joint_tolerance: Default joint tolerance (float, list or {name: tol}).
        controller: None, a registry name, a mapping with ``type``/``class``, a list of
            those, a ControllerParams or a Controller (see ``build_controller_chain``).
        notify_spawn: Emit the spawn events once the agent is built.
    """

    _spawn_params_cls: ClassVar[type[AgentSpawnParams]] = AgentSpawnParams
    is_agent: ClassVar[bool] = True
    spawned_event: ClassVar[str | None] = SimEvents.AGENT_SPAWNED
    removed_event: ClassVar[str | None] = SimEvents.AGENT_REMOVED

    def __init__(
        self,
        body_id: int,
        urdf_path: str | None = None,
        motion_mode: MotionMode | str = MotionMode.DIFFERENTIAL,
        use_fixed_base: bool = False,
        collision_mode: CollisionMode | str = CollisionMode.NORMAL_3D,
        sim_core: MultiRobotSimulationCore | None = None,
        name: str | None = None,
        user_data: dict[str, Any] | None = None,
        mass: float | None = None,
        ik_params: IKParams | None = None,
        joint_tolerance: float | list[float] | dict[str, float] | None = None,
        controller: Any = None,
        notify_spawn: bool = True,
    ) -> None:
        self._motion_mode = coerce_enum(MotionMode, motion_mode, "motion_mode")
        self.urdf_path = urdf_path
        self.use_fixed_base = bool(use_fixed_base)
        self._ik_params = ik_params if ik_params is not None else IKParams()
        self._joint_tolerance = joint_tolerance
        self._joint_set: JointSet | None = None
        self.path_visualize = False
        self.path_visualize_width = 2.0
        self.motion_result: bool | None = None
        """True: the last motion reached its goal; False: it was stopped; None: moving/never."""
        self._slot = -1
        self._controllers: list[Controller] = []
        self._plugins: list[AgentPlugin] = []
        super().__init__(
            body_id, sim_core, True, mass, collision_mode, name, user_data, register=False
        )
        chain = build_controller_chain(controller, self._motion_mode)
        if sim_core is not None:
            sim_core.add_object(self, notify=False)
        self._install_chain(chain)
        if sim_core is not None and notify_spawn:
            sim_core.world.announce(self)

    # ----- constructors -------------------------------------------------------------------

    @classmethod
    def from_params(  # type: ignore[override]  # takes AgentSpawnParams, as the seed
        cls, spawn_params: AgentSpawnParams, sim_core: MultiRobotSimulationCore | None = None
    ) -> Agent:
        """Create a URDF, mesh or virtual agent from ``spawn_params``.

        Raises:
            ValueError: for an unknown model name or bad parameters.
            FileNotFoundError: for a missing mesh file.
        """
        if not isinstance(spawn_params, AgentSpawnParams):
            raise TypeError(f"Agent.from_params: expected AgentSpawnParams, got {spawn_params!r}")
        if spawn_params.kind == "urdf":
            agent = cls.from_urdf(
                str(spawn_params.urdf_path),
                pose=spawn_params.initial_pose,
                mass=spawn_params.mass,
                motion_mode=spawn_params.motion_mode,
                use_fixed_base=spawn_params.use_fixed_base,
                collision_mode=spawn_params.collision_mode,
                sim_core=sim_core,
                name=spawn_params.name,
                user_data=dict(spawn_params.user_data),
                ik_params=spawn_params.ik_params,
                controller=spawn_params.controller,
                notify_spawn=False,
            )
        else:
            body = create_body(spawn_params, sim_core)
            agent = _construct_or_remove_body(cls, sim_core, body, **_mesh_kwargs(spawn_params))
        return cls._finish_spawn(agent, spawn_params, sim_core)

    @classmethod
    def _finish_spawn(
        cls, agent: Agent, spawn_params: AgentSpawnParams, sim_core: MultiRobotSimulationCore | None
    ) -> Agent:
        agent.pickable = spawn_params.pickable
        try:
            for i, entry in enumerate(spawn_params.plugins or []):
                agent.add_plugin(create_agent_plugin(agent, entry, where=f"plugins[{i}]"))
        except Exception:
            if sim_core is not None:  # never leave a half-built agent behind
                sim_core.remove_object(agent)
            raise
        if sim_core is not None:
            sim_core.world.announce(agent)
        return agent

    @classmethod
    def spawn_batch(  # type: ignore[override]  # takes AgentSpawnParams, as the seed
        cls, params_list: Sequence[AgentSpawnParams], sim_core: MultiRobotSimulationCore
    ) -> list[Agent]:
        """Spawn many agents fast: shape-based bodies are created in batches.

        URDF agents are loaded one by one. Input order is kept; if anything fails, nothing
        this call created is left behind.
        """
        params_list = list(params_list)
        shaped = [i for i, prm in enumerate(params_list) if prm.kind != "urdf"]
        with sim_core.batch_spawn():
            bodies = create_bodies([params_list[i] for i in shaped], sim_core)
            body_of = dict(zip(shaped, bodies, strict=True))

            def make(i: int, body: int) -> Agent:
                prm = params_list[i]
                if prm.kind == "urdf":
                    return cls.from_params(prm, sim_core)
                agent = cls(body_of[i], sim_core=sim_core, **_mesh_kwargs(prm))
                return cls._finish_spawn(agent, prm, sim_core)

            return wrap_all([body_of.get(i, -1) for i in range(len(params_list))], make, sim_core)

    @classmethod
    def from_mesh(  # type: ignore[override]  # the seed's agent parameters, not SimObject's
        cls,
        visual_shape: Any = None,
        collision_shape: Any = None,
        pose: Pose | None = None,
        mass: float = 0.0,
        motion_mode: MotionMode | str = MotionMode.DIFFERENTIAL,
        use_fixed_base: bool = False,
        collision_mode: CollisionMode | str = CollisionMode.NORMAL_3D,
        sim_core: MultiRobotSimulationCore | None = None,
        name: str | None = None,
        user_data: dict[str, Any] | None = None,
        controller: Any = None,
        notify_spawn: bool = True,
    ) -> Agent:
        """Create a mesh / primitive-shape agent."""
        params = AgentSpawnParams(
            visual_shape=visual_shape,
            collision_shape=collision_shape,
            initial_pose=pose if pose is not None else Pose([0.0, 0.0, 0.0]),
            mass=mass,
            collision_mode=collision_mode,  # type: ignore[arg-type]  # coerced in __post_init__
            name=name,
            user_data=user_data or {},
            motion_mode=motion_mode,  # type: ignore[arg-type]  # coerced in __post_init__
            use_fixed_base=use_fixed_base,
            controller=controller,
        )
        return cls.from_params(params, sim_core)

    @classmethod
    def from_urdf(
        cls,
        urdf_path: str,
        pose: Pose | None = None,
        mass: float | None = None,
        motion_mode: MotionMode | str = MotionMode.DIFFERENTIAL,
        use_fixed_base: bool = False,
        collision_mode: CollisionMode | str = CollisionMode.NORMAL_3D,
        sim_core: MultiRobotSimulationCore | None = None,
        name: str | None = None,
        user_data: dict[str, Any] | None = None,
        ik_params: IKParams | None = None,
        joint_tolerance: float | list[float] | dict[str, float] | None = None,
        controller: Any = None,
        notify_spawn: bool = True,
    ) -> Agent:
        """Load a URDF (a path or a model name such as "mobile_robot" or "panda").

        ``mass=None`` keeps the URDF's masses; ``mass=0.0`` makes every link kinematic.

        Raises:
            ValueError: for an unknown model name, naming the known ones.
        """
        path = resolve_model(urdf_path)
        pose = pose if pose is not None else Pose([0.0, 0.0, 0.0])
        client = 0 if sim_core is None else sim_core.client
        pos, orn = pose.as_position_orientation()
        try:
            body = p.loadURDF(
                path, pos, orn, useFixedBase=bool(use_fixed_base), physicsClientId=client
            )
        except p.error as exc:
            raise ValueError(f"urdf_path {path!r}: PyBullet could not load it ({exc})") from exc
        if mass == 0.0:
            for link in range(-1, p.getNumJoints(body, physicsClientId=client)):
                p.changeDynamics(body, link, mass=0.0, physicsClientId=client)
        return _construct_or_remove_body(
            cls,
            sim_core,
            body,
            urdf_path=path,
            motion_mode=motion_mode,
            use_fixed_base=use_fixed_base,
            collision_mode=collision_mode,
            name=name,
            user_data=user_data,
            mass=mass,
            ik_params=ik_params,
            joint_tolerance=joint_tolerance,
            controller=controller,
            notify_spawn=notify_spawn,
        )

    # ----- controllers --------------------------------------------------------------------

    def _install_chain(self, chain: list[Controller]) -> None:
        old = self._controllers
        for ctrl in old:
            if not any(ctrl is c for c in chain):
                ctrl.on_remove(self)
        self._release_slot()
        self._controllers = chain
        base = self.controller
        sim = self.sim_core
        if sim is not None and isinstance(base, KinematicController) and base.vectorized:
            self._slot = sim.fleet.add_slot(self, base.kind)
        for ctrl in chain:
            if not any(ctrl is c for c in old):
                ctrl.on_install(self)
        if sim is not None:
            sim.fleet.track(self)

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
        controller.on_install(self)
        if self.sim_core is not None:
            self.sim_core.fleet.track(self)

    def remove_controller(self, controller_or_cls: Controller | type[Controller]) -> bool:
        """Remove a high-level controller by instance or class (never the base)."""
        for i, ctrl in enumerate(self._controllers[1:], start=1):
            if ctrl is controller_or_cls or (
                isinstance(controller_or_cls, type) and isinstance(ctrl, controller_or_cls)
            ):
                del self._controllers[i]
                ctrl.on_remove(self)
                if self.sim_core is not None:
                    self.sim_core.fleet.track(self)
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
            ctrl.compute(self, dt)
        base = self.controller
        if base is not None and not (isinstance(base, KinematicController) and base.vectorized):
            base.compute(self, dt)

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
        base.set_path(self, waypoints, chosen, bool(final_orientation_align))
        if self.path_visualize and self.sim_core is not None and self.sim_core.is_gui:
            Path(waypoints).visualize(
                line_width=self.path_visualize_width, physics_client_id=self.sim_core.client
            )

    def set_goal_pose(self, goal: Pose, direction: MovementDirection | str | None = None) -> None:
        """Drive to ``goal`` (a one-waypoint path)."""
        if not isinstance(goal, Pose):
            raise ValueError(f"set_goal_pose: expected a Pose, got {goal!r}")
        self.set_path([goal], direction=direction)

    def set_cmd_vel(
        self, vx: float = 0.0, vy: float = 0.0, wz: float = 0.0, vz: float = 0.0
    ) -> None:
        """Follow a body-frame velocity command (m/s, rad/s) until stopped or given a path.

        Raises:
            ValueError: for a sideways command (``vy``) on a differential robot.
        """
        base = self._base("set_cmd_vel")
        if base is None:
            return
        if vy != 0.0 and base.motion_mode is MotionMode.DIFFERENTIAL:
            raise ValueError(
                f"set_cmd_vel: vy={vy!r} but a differential robot cannot move sideways"
            )
        self.motion_result = None
        base.set_velocity(self, (float(vx), float(vy), float(vz), float(wz)))

    def stop(self) -> None:
        """Stop moving and forget the goal and path."""
        base = self.controller
        if isinstance(base, KinematicController) and self.sim_core is not None:
            base.stop(self)

    @property
    def is_moving(self) -> bool:
        """Whether the agent follows a path or a non-zero velocity command."""
        base = self.controller
        return (
            isinstance(base, KinematicController)
            and self.sim_core is not None
            and base.is_moving(self)
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
            base.goal_pose(self)
            if isinstance(base, KinematicController) and self.sim_core
            else None
        )

    @property
    def path(self) -> list[Pose]:
        """Waypoints not reached yet; empty when idle."""
        base = self.controller
        return (
            base.remaining_path(self)
            if isinstance(base, KinematicController) and self.sim_core
            else []
        )

    @property
    def current_waypoint_index(self) -> int:
        """Index (in the path given to ``set_path``) of the waypoint being approached."""
        base = self.controller
        return (
            base.waypoint_index(self)
            if isinstance(base, KinematicController) and self.sim_core
            else 0
        )

    def note_motion_end(self, reached: bool) -> None:
        """Record how the last motion ended (called by the simulation)."""
        self.motion_result = reached

    def report_motion_end(self, reached: bool) -> None:
        """For custom base controllers: the agent stopped (``reached``: at its goal)."""
        if self.sim_core is not None:
            self.sim_core.fleet.motion_ended(self, reached)

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

    # ----- actions ------------------------------------------------------------------------

    def _queue(self) -> Any:
        if self.sim_core is None:
            raise ValueError(f"actions need a simulation; {self!r} is not part of one")
        return self.sim_core.fleet.actions

    def add_action(self, action: Action) -> None:
        """Queue ``action``; actions run one after another in the order added."""
        self._queue().submit(self, action)

    def add_action_sequence(self, actions: Sequence[Action]) -> None:
        """Queue several actions in order."""
        for action in actions:
            self.add_action(action)

    def clear_actions(self) -> None:
        """Cancel the current action and drop the queued ones."""
        self._queue().clear(self)

    def get_current_action(self) -> Action | None:
        """The action being executed, or None."""
        return None if self.sim_core is None else self._queue().current(self)

    def get_action_queue_size(self) -> int:
        """Actions waiting behind the current one."""
        return 0 if self.sim_core is None else int(self._queue().queued(self))

    def is_action_queue_empty(self) -> bool:
        """No action running and none queued."""
        return True if self.sim_core is None else bool(self._queue().is_idle(self))

    # ----- plugins and battery --------------------------------------------------------------

    @property
    def plugins(self) -> list[AgentPlugin]:
        """Per-agent plugins, in the order added."""
        return list(self._plugins)

    def add_plugin(self, plugin: AgentPlugin) -> None:
        """Attach a plugin built for this agent.

        Raises:
            ValueError: if the plugin was built for another agent.
        """
        if plugin.agent is not self:
            raise ValueError(
                f"add_plugin: {type(plugin).__name__} is bound to {plugin.agent!r}, not {self!r}"
            )
        self._plugins.append(plugin)
        if self.sim_core is not None:
            self.sim_core.fleet.track(self)

    def remove_plugin(self, plugin_or_cls: AgentPlugin | type[AgentPlugin]) -> bool:
        """Remove a plugin by instance or class; return whether one was removed."""
        for i, plugin in enumerate(self._plugins):
            if plugin is plugin_or_cls or (
                isinstance(plugin_or_cls, type) and isinstance(plugin, plugin_or_cls)
            ):
                del self._plugins[i]
                plugin.on_remove()
                if self.sim_core is not None:
                    self.sim_core.fleet.track(self)
                return True
        return False

    def get_plugin(self, cls: type[AgentPlugin]) -> AgentPlugin | None:
        """First plugin that is an instance of ``cls``."""
        return next((pl for pl in self._plugins if isinstance(pl, cls)), None)

    def step_plugins(self, dt: float) -> None:
        """Step every plugin (called by the simulation after motion)."""
        for plugin in self._plugins:
            plugin.on_step(dt)

    @property
    def battery_plugin(self) -> BatteryPlugin | None:
        """The BatteryPlugin, or None."""
        plugin = self.get_plugin(BatteryPlugin)
        return plugin if isinstance(plugin, BatteryPlugin) else None

    @property
    def battery_soc(self) -> float:
        """State of charge in [0, 1]; 1.0 without a battery."""
        battery = self.battery_plugin
        return 1.0 if battery is None else battery.soc

    @property
    def is_charging(self) -> bool:
        """Whether the battery is charging."""
        battery = self.battery_plugin
        return battery is not None and battery.charging

    def set_charging(self, charging: bool) -> None:
        """Start or stop charging (no-op without a battery)."""
        battery = self.battery_plugin
        if battery is not None:
            battery.charging = bool(charging)

    # ----- lifecycle ----------------------------------------------------------------------

    def on_removed(self) -> None:
        """Leave the fleet: actions dropped, engine slot freed, plugins told."""
        sim = self.sim_core
        if sim is not None:
            sim.fleet.forget(self)
            sim.joint_motion.forget(self)
        self._release_slot()
        for plugin in self._plugins:
            plugin.on_remove()
