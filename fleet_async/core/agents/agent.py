"""Agent: a SimObject that moves under a controller chain and runs an action queue.

Motion is delegated to the base controller (index 0 of the chain, ``agent_motion.py``); the
built-in omni and differential controllers are advanced for all agents at once by the
simulation's kinematic engine (``motion/kinematics.py``), so an Agent's own per-step Python
cost is zero unless it has high-level controllers or plugins. Actions go through the
simulation's event-driven queue (``actions/action_queue.py``); joints and IK are in
``agent_joints.py``, the awaitable mission commands in ``missions/agent_missions.py``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar

from fleet_async.core.actions.action import Action
from fleet_async.core.agents.agent_joints import AgentJointsApi
from fleet_async.core.agents.agent_motion import AgentMotionApi
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.agents.agent_plugins import AgentPlugin, BatteryPlugin, create_agent_plugin
from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.types import CollisionMode, MotionMode, coerce_enum
from fleet_async.core.bodies.models import resolve_model
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.bodies.spawning import construct, reserve_bodies, reserve_body, wrap_all
from fleet_async.core.bodies.urdf_spawn import reserve_urdf_body
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.missions.agent_missions import AgentMissionApi
from fleet_async.core.motion.chain import build_controller_chain
from fleet_async.core.motion.controllers import Controller
from fleet_async.core.motion.ik import IKParams
from fleet_async.core.motion.joints import JointSet, check_tolerance_spec

if TYPE_CHECKING:
    from fleet_async.core.agents.host import AgentHost

__all__ = ["Agent", "AgentSpawnParams", "IKParams"]


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


class Agent(AgentMissionApi, AgentJointsApi, AgentMotionApi, SimObject):
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
    is_robot: ClassVar[bool] = True
    """Whether fleet figures (``sim.kpis()``) count agents of this class as robots; devices
    (doors, lifts, workcells) are agents that are not."""
    spawned_event: ClassVar[str | None] = SimEvents.AGENT_SPAWNED
    removed_event: ClassVar[str | None] = SimEvents.AGENT_REMOVED
    sim_core: AgentHost | None
    """The simulation the agent is in (None outside one or once removed)."""

    def __init__(
        self,
        body_id: int,
        urdf_path: str | None = None,
        motion_mode: MotionMode | str = MotionMode.DIFFERENTIAL,
        use_fixed_base: bool = False,
        collision_mode: CollisionMode | str = CollisionMode.NORMAL_3D,
        sim_core: AgentHost | None = None,
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
        self._ik_params = ik_params  # the defaults are made on first use (most agents: never)
        check_tolerance_spec(joint_tolerance, "Agent.joint_tolerance")
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
        cls, spawn_params: AgentSpawnParams, sim_core: AgentHost | None = None
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
            body, deferred = reserve_body(spawn_params, sim_core)
            kwargs = _mesh_kwargs(spawn_params)
            agent = construct(
                lambda b: cls(b, sim_core=sim_core, **kwargs), body, deferred, sim_core
            )
        return cls._finish_spawn(agent, spawn_params, sim_core)

    @classmethod
    def _finish_spawn(
        cls, agent: Agent, spawn_params: AgentSpawnParams, sim_core: AgentHost | None
    ) -> Agent:
        agent.pickable = spawn_params.pickable
        try:
            for i, entry in enumerate(spawn_params.plugins or []):
                agent.add_plugin(create_agent_plugin(agent, entry, where=f"plugins[{i}]"))
            if spawn_params.safety_field is not None and sim_core is not None:
                sim_core.safety.enable(agent, spawn_params.safety_field)
        except Exception:
            if sim_core is not None:  # never leave a half-built agent behind
                sim_core.remove_object(agent)
            raise
        if sim_core is not None:
            sim_core.world.announce(agent)
        return agent

    @classmethod
    def spawn_batch(  # type: ignore[override]  # takes AgentSpawnParams, as the seed
        cls, params_list: Sequence[AgentSpawnParams], sim_core: AgentHost
    ) -> list[Agent]:
        """Spawn many agents fast: shape-based bodies are left pending or created in batches
        (as ``from_params`` would).

        URDF agents are spawned one by one (``from_urdf``). Input order is kept; if anything
        fails, nothing this call created is left behind.
        """
        params_list = list(params_list)
        shaped = [i for i, prm in enumerate(params_list) if prm.kind != "urdf"]
        with sim_core.batch_spawn():
            reserved = reserve_bodies([params_list[i] for i in shaped], sim_core)
            body_of = dict(zip(shaped, reserved, strict=True))

            def make(i: int, body: int) -> Agent:
                prm = params_list[i]
                if prm.kind == "urdf":
                    return cls.from_params(prm, sim_core)
                kwargs = _mesh_kwargs(prm)
                agent = construct(
                    lambda b: cls(b, sim_core=sim_core, **kwargs), body, body_of[i][1], sim_core
                )
                return cls._finish_spawn(agent, prm, sim_core)

            bodies = [body_of[i][0] if i in body_of else -1 for i in range(len(params_list))]
            return wrap_all(bodies, make, sim_core)

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
        sim_core: AgentHost | None = None,
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
        sim_core: AgentHost | None = None,
        name: str | None = None,
        user_data: dict[str, Any] | None = None,
        ik_params: IKParams | None = None,
        joint_tolerance: float | list[float] | dict[str, float] | None = None,
        controller: Any = None,
        notify_spawn: bool = True,
    ) -> Agent:
        """Load a URDF (a path or a model name such as "mobile_robot" or "panda").

        ``mass=None`` keeps the URDF's masses; ``mass=0.0`` makes every link kinematic. On a
        headless simulation, a robot of a model the simulation loaded before whose body is
        kinematic (physics off or ``mass=0.0``) waits for its body: the model is not loaded
        again until something needs PyBullet's view (``bodies/urdf_spawn.py``).

        Raises:
            ValueError: for an unknown model name, naming the known ones.
        """
        path = resolve_model(urdf_path)
        pose = pose if pose is not None else Pose([0.0, 0.0, 0.0])
        body, deferred, urdf_mass = reserve_urdf_body(path, pose, use_fixed_base, mass, sim_core)
        kwargs: dict[str, Any] = {
            "urdf_path": path,
            "motion_mode": motion_mode,
            "use_fixed_base": use_fixed_base,
            "collision_mode": collision_mode,
            "name": name,
            "user_data": user_data,
            # A pending body has no masses to read yet: the model's, which it will have.
            "mass": urdf_mass if mass is None else mass,
            "ik_params": ik_params,
            "joint_tolerance": joint_tolerance,
            "controller": controller,
            "notify_spawn": notify_spawn,
        }
        return construct(lambda b: cls(b, sim_core=sim_core, **kwargs), body, deferred, sim_core)

    # ----- actions ------------------------------------------------------------------------

    def _queue(self) -> Any:
        self.check_not_removed("actions")
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

    def has_plugins(self) -> bool:
        """Whether any per-agent plugin is attached."""
        return bool(self._plugins)

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
