"""SimulationKernel: the clock, the step loop and the objects it moves.

The step loop is the only clock: ``sim_time == step_count * timestep``. One step runs these
phases in order, each a call into the module that owns it:

1. ``events_pre_step``  - PRE_STEP event.
2. ``callbacks``        - simulation callbacks, plugins and per-object callbacks that are due.
3. ``safety_fields``    - agents' safety fields hold or slow them (``collision/safety.py``;
   free while no agent has fields).
4. ``agent_update``     - PRE_UPDATE, motion systems and overridden ``update(dt)``, POST_UPDATE.
5. ``attachments``      - attached objects follow their parent links.
6. ``pose_flush``       - push the step's poses to PyBullet (only with physics, the GUI or
   ``sync_pybullet_every_step``; otherwise PyBullet is synced lazily).
7. ``step_simulation``  - PyBullet dynamics (only present when ``physics=True``).
8. ``collision_check``  - the collision pipeline, when due (``collision/``).
9. ``events_post_step`` - the clock advances, POST_STEP event, step observers (then, with
   ``sync_pybullet_every_step``, what its handlers wrote is pushed too).

Profiling (``return_profiling``, ``profiling.py``) runs the same phases through a timer.
Real-time pacing, the monitor and GUI input wrap this loop from the layer above (``view/``);
they are not branches inside it. ``MultiRobotSimulationCore`` (``core/simulation.py``) is this
kernel plus scenario loading, world loading, recording, the monitor, the GUI and
``run_simulation``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

import numpy as np

from fleet_async.core.agents.fleet import FleetMotion
from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.params import SimulationParams
from fleet_async.core.base.scheduling import PeriodicSchedule
from fleet_async.core.collision.api import CollisionApi
from fleet_async.core.collision.safety import SafetyFields
from fleet_async.core.collision.system import CollisionSystem
from fleet_async.core.missions.mission_api import SimEventBus, SimMissionApi
from fleet_async.core.motion.joints import JointMotion
from fleet_async.core.sim.idle import IdleApi, IdleSteps
from fleet_async.core.sim.objects_api import ObjectsApi
from fleet_async.core.sim.plugins import SimPlugin, as_plugin
from fleet_async.core.sim.profiling import MemoryProfiler, StepProfiler
from fleet_async.core.sim.pybullet_view import PyBulletViewApi
from fleet_async.core.sim.streams import RandomStreamsApi
from fleet_async.core.world.attachments import AttachmentSet
from fleet_async.core.world.backend import PyBulletBackend
from fleet_async.core.world.state import KinematicState
from fleet_async.core.world.world import World

if TYPE_CHECKING:
    from typing_extensions import Self

    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.bodies.sim_object import SimObject

__all__ = ["MotionSystem", "SimulationKernel"]

logger = logging.getLogger(__name__)

_LOG_LEVELS = {"debug": 10, "info": 20, "warn": 30, "warning": 30, "error": 40, "critical": 50}

_Sim = TypeVar("_Sim", bound="SimulationKernel")


class MotionSystem(Protocol):
    """Something that advances many objects per step (e.g. a vectorised controller)."""

    def advance(self, dt: float) -> None:
        """Move every object this system owns by one step of ``dt`` seconds."""


class SimulationKernel(
    IdleApi, SimMissionApi, CollisionApi, ObjectsApi, PyBulletViewApi, RandomStreamsApi
):
    """The clock, the step loop and what it moves (objects, agents, plugins, managers).

    Only ever built as a :class:`~fleet_async.core.simulation.MultiRobotSimulationCore`, which
    adds the layers above; collaborators are handed the kernel, each naming what it uses of it
    with a protocol of its own floor.

    Args:
        params: Simulation settings (default ``SimulationParams()``).
        collision_color: RGBA used to highlight colliding objects when
            ``enable_collision_color_change`` is on.
    """

    def __init__(
        self, params: SimulationParams | None = None, collision_color: Sequence[float] | None = None
    ) -> None:
        self._params = params if params is not None else SimulationParams()
        if not isinstance(self._params, SimulationParams):
            raise TypeError(
                f"MultiRobotSimulationCore: params must be SimulationParams, got {params!r}"
            )
        logging.getLogger("fleet_async").setLevel(_LOG_LEVELS[self._params.log_level])
        self.collision_color = (
            list(collision_color) if collision_color is not None else [1.0, 0.0, 0.0, 1.0]
        )
        self.events: SimEventBus = SimEventBus(self)
        self.rng = np.random.default_rng(self._params.seed)
        self._backend = PyBulletBackend(self._params)
        self._backend.connect()
        # Collaborators are handed the kernel and name what they use of it with a protocol of
        # their own floor (``world/host.py``, ``agents/host.py``, ``collision/host.py``, ...).
        self._world: World[SimObject] = World(
            self, self._backend, self.events, self._params.physics
        )
        self._fleet = FleetMotion(self)
        self._collision = CollisionSystem(self, self._push_dirty)
        self._safety = SafetyFields(self, self._collision, self._fleet)
        self._callbacks = PeriodicSchedule()
        self._plugin_schedule = PeriodicSchedule()
        self._plugins: list[SimPlugin] = []
        self._managers: list[Any] = []
        self._joint_motion = JointMotion(self._fleet.wake_action)
        self._motion_systems: list[MotionSystem] = [self._fleet, self._joint_motion]
        self._step_observers: list[Callable[[int], None]] = []
        self._early_observers: list[Callable[[int], None]] = []  # before POST_STEP handlers
        self._step_count = 0
        self._collision_count = 0
        self._paused = False
        self._initialized = False
        self._profiler = StepProfiler(
            self._params.profiling_interval, self._params.enable_time_profiling
        )
        self._memory = MemoryProfiler(self._params.enable_memory_profiling)
        self._last_profiling: Mapping[str, Any] | None = None
        self._collision_timings: dict[str, float] | None = None
        self._profiling_step = False
        self._idle = IdleSteps(
            self._params.timestep,
            self.events,
            (self._callbacks, self._plugin_schedule),
            self._world,
            self._fleet,
            self._collision,
            lambda: self._motion_systems,
            self._joint_motion,
            lambda: self.is_gui or self._params.physics or self._profiler.log_summary,
        )
        # PyBullet sees the step's poses only where something needs them: a physics step, the
        # GUI, or a script that asked for it (sync_pybullet_every_step).
        flush = self._params.physics or self.is_gui or self._params.sync_pybullet_every_step
        self._phases: tuple[tuple[str, Callable[[], None]], ...] = (
            ("events_pre_step", self._phase_pre_step),
            ("callbacks", self._phase_callbacks),
            ("safety_fields", self._safety.run),
            ("agent_update", self._phase_motion),
            ("attachments", self._world.attachments.follow_all),
            *((("pose_flush", self.sync_pybullet),) if flush else ()),
            *((("step_simulation", self._phase_physics),) if self._params.physics else ()),
            ("collision_check", self._phase_collision),
            ("events_post_step", self._phase_post_step),
        )

    # ----- read-only state ----------------------------------------------------------------

    @property
    def params(self) -> SimulationParams:
        """The simulation settings."""
        return self._params

    @property
    def state(self) -> KinematicState:
        """The state store holding every object's row (for vectorised collaborators)."""
        return self._world.store

    @property
    def fleet(self) -> FleetMotion:
        """Agents' motion: the kinematic engine, action queues and per-agent controllers."""
        return self._fleet

    @property
    def safety(self) -> SafetyFields:
        """Agents' safety fields: who has them, who is stopped, deadlock settings."""
        return self._safety

    @property
    def action_time(self) -> float:
        """The action queues' clock (s): the sim time the actions being advanced run at, which
        inside a step is that step's end for a timed action that ends with it."""
        return self._fleet.actions.now

    @property
    def joint_motion(self) -> JointMotion[Agent]:
        """Moves URDF agents' joints towards their targets each step."""
        return self._joint_motion

    @property
    def world(self) -> World[SimObject]:
        """Objects, rows and attachments (what SimObject handles call back into)."""
        return self._world

    @property
    def attachments(self) -> AttachmentSet[SimObject]:
        """Every parent/child attachment."""
        return self._world.attachments

    @property
    def step_count(self) -> int:
        """Steps run since the last ``initialize_simulation``."""
        return self._step_count

    @property
    def sim_time(self) -> float:
        """Simulation time in seconds: ``step_count * timestep`` (never an accumulated float)."""
        return self._step_count * self._params.timestep

    @property
    def in_step(self) -> bool:
        """Whether ``step_once`` is running."""
        return self._world.in_step

    @property
    def is_paused(self) -> bool:
        """Whether ``step_once`` is currently skipped."""
        return self._paused

    @property
    def enable_memory_profiling(self) -> bool:
        """Whether memory profiling is on."""
        return self._memory.enabled

    @property
    def plugins(self) -> list[SimPlugin]:
        """Registered plugins, in registration order."""
        return list(self._plugins)

    # ----- callbacks, plugins, managers, motion systems -----------------------------------

    def register_callback(
        self,
        callback: Callable[[Self, float], Any],
        frequency: float | None = None,
    ) -> None:
        """Call ``callback(sim, dt)`` every step (None) or at ``frequency`` Hz of sim time."""
        self._callbacks.add(callback, frequency, owner="register_callback", now=self.sim_time)

    def unregister_callback(self, callback_func: Callable[..., Any]) -> bool:
        """Remove a callback; return whether it was registered."""
        return self._callbacks.remove(callback_func)

    def register_plugin(
        self,
        plugin_or_cls: SimPlugin | type[SimPlugin],
        config: dict[str, Any] | None = None,
        frequency: float | None = None,
    ) -> SimPlugin:
        """Register a plugin instance, or instantiate a SimPlugin subclass with ``config``.

        Raises:
            TypeError: if the argument is not a SimPlugin or SimPlugin subclass.
            ValueError: if ``config`` is given with an instance.
        """
        plugin = as_plugin(plugin_or_cls, self, config)
        freq = frequency if frequency is not None else plugin.frequency
        self._plugin_schedule.add(
            plugin.on_step,
            freq,
            owner=f"register_plugin({type(plugin).__name__})",
            now=self.sim_time,
        )
        self._plugins.append(plugin)
        plugin.on_init()
        return plugin

    def register_manager(self, manager: Any) -> None:
        """Keep ``manager`` in sync with removals and resets; duplicate calls are ignored."""
        if any(m is manager for m in self._managers):
            return
        manager.sim_core = self
        self._managers.append(manager)

    def unregister_manager(self, manager: Any) -> bool:
        """Forget a manager; return whether it was registered."""
        for i, m in enumerate(self._managers):
            if m is manager:
                del self._managers[i]
                return True
        return False

    def get_manager(self, name: str) -> Any | None:
        """The registered manager called ``name``, or None."""
        return next((m for m in self._managers if getattr(m, "name", None) == name), None)

    def add_motion_system(self, system: MotionSystem) -> None:
        """Advance ``system`` in every step's motion phase (vectorised controllers)."""
        if system not in self._motion_systems:
            self._motion_systems.append(system)

    def remove_motion_system(self, system: MotionSystem) -> None:
        """Stop advancing ``system``."""
        if system in self._motion_systems:
            self._motion_systems.remove(system)

    def add_step_observer(
        self, observer: Callable[[int], None], *, before_handlers: bool = False
    ) -> None:
        """Call ``observer(step_count)`` at the end of every step, after the POST_STEP handlers
        (``before_handlers``: before them, seeing the state as the step's phases left it).

        An observer only watches (a trace writer, the KPI collector): it must not change the
        simulation. Unlike a POST_STEP handler it therefore does not make every step count
        for :meth:`idle_steps`, so the drivers still skip empty steps; it hears of a skipped
        span from the STEPS_SKIPPED event instead.
        """
        observers = self._early_observers if before_handlers else self._step_observers
        if observer not in observers:
            observers.append(observer)

    def remove_step_observer(self, observer: Callable[[int], None]) -> bool:
        """Stop calling ``observer``; return whether it was added."""
        for observers in (self._step_observers, self._early_observers):
            if observer in observers:
                observers.remove(observer)
                return True
        return False

    # ----- the step loop ------------------------------------------------------------------

    def step_once(self, return_profiling: bool = False) -> dict[str, Any] | None:
        """Run one step (skipped while paused).

        Args:
            return_profiling: Return this step's timings in ms: the reference API's keys
                (``phase1_update``, ``phase2_pose_flush``, ``phase3_aabb_grid_flush``,
                ``agent_update``, ``callbacks``, ``step_simulation``, ``collision_check``,
                ``collision_breakdown`` when the collision check ran, ``events_pre_step``,
                ``events_post_step``, ``events_collision``, ``monitor_update``, ``total``),
                fleet_async's ``attachments`` and ``safety_fields``, and fields added by
                ``record_profiling`` (see ``sim/profiling.py``).

        Returns:
            The timings when ``return_profiling`` is set, else None.
        """
        if self._paused:
            return None
        if not self._initialized:
            self.initialize_simulation()
        self._world.in_step = True
        self._collision_timings = None
        self._profiling_step = return_profiling or self._profiler.log_summary
        try:
            if self._profiling_step:
                timings: dict[str, Any] | None = self._profiler.run(
                    self._phases, lambda: self._collision_timings
                )
            else:
                for _, phase in self._phases:
                    phase()
                self._profiler.discard_custom()
                timings = None
        finally:
            self._world.in_step = False
        self._last_profiling = None if timings is None else MappingProxyType(timings)
        return timings if return_profiling else None

    @property
    def last_profiling(self) -> Mapping[str, Any] | None:
        """The last step's timings (read-only) if it was profiled, else None."""
        return self._last_profiling

    def _phase_pre_step(self) -> None:
        if self.events.has_handlers(SimEvents.PRE_STEP):
            self.events.emit(
                SimEvents.PRE_STEP,
                sim=self,
                step=self._step_count,
                dt=self._params.timestep,
                sim_time=self.sim_time,
            )

    def _phase_callbacks(self) -> None:
        now, dt = self.sim_time, self._params.timestep
        for callback, elapsed in self._callbacks.due(now, dt):
            callback(self, elapsed)
        for on_step, elapsed in self._plugin_schedule.due(now, dt):
            on_step(elapsed)
        self._world.run_object_callbacks(self._step_count, now, dt)

    def _phase_motion(self) -> None:
        dt = self._params.timestep
        if self.events.has_handlers(SimEvents.PRE_UPDATE):
            self.events.emit(SimEvents.PRE_UPDATE, sim=self, dt=dt)
        world = self._world
        before = world.emit_pre_update(dt) if world.has_update_listeners() else None
        for system in tuple(self._motion_systems):
            system.advance(dt)
        for obj in world.updaters():
            obj.update(dt)
        if before is not None:
            world.emit_post_update(dt, before)
        if self.events.has_handlers(SimEvents.POST_UPDATE):
            self.events.emit(SimEvents.POST_UPDATE, sim=self, dt=dt)

    def _phase_physics(self) -> None:
        self._backend.step_physics()
        self._world.read_back_dynamic()

    def _phase_collision(self) -> None:
        if self._collision.is_due(self._step_count, self._params.timestep):
            if self._profiling_step:  # the profile reports the check's own breakdown
                _, self._collision_timings = self._collision.check()
            else:
                self._collision.run()

    def _phase_post_step(self) -> None:
        self._step_count += 1
        if self._early_observers:
            for observer in tuple(self._early_observers):
                observer(self._step_count)
        if self.events.has_handlers(SimEvents.POST_STEP):
            self.events.emit(
                SimEvents.POST_STEP,
                sim=self,
                step=self._step_count,
                dt=self._params.timestep,
                sim_time=self.sim_time,
            )
        if self._step_observers:
            for observer in tuple(self._step_observers):
                observer(self._step_count)
        if self._params.sync_pybullet_every_step:  # what POST_STEP handlers wrote, too
            self.sync_pybullet()

    # ----- PyBullet's view, profiling -------------------------------------------------------

    def record_profiling(self, name: str, value_ms: float) -> None:
        """Add ``value_ms`` to custom profiling field ``name`` for the current step."""
        self._profiler.record(name, value_ms)

    def get_memory_usage(self) -> dict[str, float] | None:
        """``{"current_mb", "peak_mb"}`` of the Python heap; None unless memory profiling is on."""
        return self._memory.usage()

    # ----- running ------------------------------------------------------------------------

    def initialize_simulation(self) -> None:
        """Reset the clock and counters to zero and restart every schedule."""
        self._step_count = 0
        self._collision_count = 0
        self._callbacks.reset()
        self._plugin_schedule.reset()
        for obj in self._world.objects_with_callbacks():
            obj.reset_callbacks()
        self._backend.set_rendering(True)
        self._initialized = True

    def pause(self) -> None:
        """Pause: ``step_once`` does nothing until :meth:`resume`."""
        if not self._paused:
            self._paused = True
            self.events.emit(SimEvents.PAUSED, sim=self)

    def resume(self) -> None:
        """Resume after :meth:`pause`."""
        if self._paused:
            self._paused = False
            self.events.emit(SimEvents.RESUMED, sim=self)

    def reset(self, seed: int | None = None) -> None:
        """Remove every object, rebuild the PyBullet world and zero the clock.

        Callbacks, plugins (which get ``on_reset``) and managers (cleared) are kept. The random
        generator is reseeded with ``seed``, or with ``params.seed``.
        """
        self._fleet.reset()  # first: unfinished actions end CANCELLED while agents are bound
        self._joint_motion.reset()
        removed = self._world.clear()
        self._collision.reset()
        self._safety.reset()
        for manager in self._managers:
            manager.clear()
        self._backend.reset_world()
        self._reset_random_streams(self._params.seed if seed is None else seed)
        self.initialize_simulation()
        for obj in removed:
            self.events.emit(SimEvents.OBJECT_REMOVED, sim=self, obj=obj)
        for plugin in self._plugins:
            plugin.on_reset()

    def close(self) -> None:
        """End the missions a run left suspended, then disconnect from PyBullet; the
        simulation cannot step afterwards."""
        try:
            self.end_missions_before_close()
        finally:
            self._memory.stop()
            self._backend.disconnect()

    def __enter__(self: _Sim) -> _Sim:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
