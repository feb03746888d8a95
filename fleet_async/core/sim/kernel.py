"""SimulationKernel: the clock, the step loop and the objects it moves.

The step loop is the only clock: ``sim_time == step_count * timestep``. One step runs these
phases in order, each a call into the module that owns it:

1. ``events_pre_step``  - PRE_STEP event.
2. ``callbacks``        - simulation callbacks, plugins and per-object callbacks that are due.
3. ``agent_update``     - PRE_UPDATE, motion systems and overridden ``update(dt)``, POST_UPDATE.
4. ``attachments``      - attached objects follow their parent links.
5. ``step_simulation``  - PyBullet dynamics (only present when ``physics=True``).
6. ``collision_check``  - the collision pipeline, when due (``collision/``).
7. ``events_post_step`` - the clock advances, the GUI is synced, POST_STEP event.

Profiling (``return_profiling``, ``profiling.py``) runs the same phases through a timer.
Real-time pacing, the monitor and GUI input wrap this loop from the layer above (``view/``);
they are not branches inside it. ``MultiRobotSimulationCore`` (``core/simulation.py``) is this
kernel plus scenario loading, world loading, recording, the monitor, the GUI and
``run_simulation``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, TypeVar, cast

import numpy as np

from fleet_async.core.agents.fleet import FleetMotion
from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.scheduling import PeriodicSchedule
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.collision.api import CollisionApi
from fleet_async.core.collision.system import CollisionSystem
from fleet_async.core.missions.mission_api import SimEventBus, SimMissionApi
from fleet_async.core.motion.joints import JointMotion
from fleet_async.core.sim.idle import IdleApi, IdleSteps
from fleet_async.core.sim.params import SimulationParams
from fleet_async.core.sim.plugins import SimPlugin
from fleet_async.core.sim.profiling import MemoryProfiler, StepProfiler
from fleet_async.core.sim.registry import MotionSystem, RegistryApi
from fleet_async.core.world.attachments import AttachmentSet
from fleet_async.core.world.backend import PyBulletBackend
from fleet_async.core.world.state import KinematicState
from fleet_async.core.world.world import World

if TYPE_CHECKING:
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["MotionSystem", "SimulationKernel"]

logger = logging.getLogger(__name__)

_LOG_LEVELS = {"debug": 10, "info": 20, "warn": 30, "warning": 30, "error": 40, "critical": 50}

_Sim = TypeVar("_Sim", bound="SimulationKernel")


class SimulationKernel(IdleApi, RegistryApi, SimMissionApi, CollisionApi):
    """The clock, the step loop and what it moves (objects, agents, plugins, managers).

    Only ever built as a :class:`~fleet_async.core.simulation.MultiRobotSimulationCore`, which
    adds the layers above; collaborators are handed the simulation as that class.

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
        # Collaborators are handed the simulation as the class it is always built as.
        sim = cast("MultiRobotSimulationCore", self)
        self._world = World(sim, self._backend, self.events, self._params.physics)
        self._fleet = FleetMotion(sim)
        self._collision = CollisionSystem(sim, self._push_dirty)
        self._callbacks = PeriodicSchedule()
        self._plugin_schedule = PeriodicSchedule()
        self._plugins: list[SimPlugin] = []
        self._managers: list[Any] = []
        self._joint_motion = JointMotion(self._fleet.wake_action)
        self._motion_systems: list[MotionSystem] = [self._fleet, self._joint_motion]
        self._step_count = 0
        self._collision_count = 0
        self._physics_bodies = self._params.physics or self._backend.is_gui
        self._paused = False
        self._initialized = False
        self._profiler = StepProfiler(
            self._params.profiling_interval, self._params.enable_time_profiling
        )
        self._memory = MemoryProfiler(self._params.enable_memory_profiling)
        self._idle = IdleSteps(
            self._params.timestep,
            self.events,
            (self._callbacks, self._plugin_schedule),
            self._world,
            self._fleet,
            self._collision,
            lambda: self._motion_systems,
            self._joint_motion,
            lambda: self._backend.is_gui or self._params.physics or self._profiler.log_summary,
        )
        self._phases: tuple[tuple[str, Callable[[], None]], ...] = (
            ("events_pre_step", self._phase_pre_step),
            ("callbacks", self._phase_callbacks),
            ("agent_update", self._phase_motion),
            ("attachments", self._world.attachments.follow_all),
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
    def client(self) -> int:
        """PyBullet physics client id, for raw ``pybullet`` calls (``physicsClientId=``).

        Bodies of objects spawned since the last step are created first, so raw calls see
        every object."""
        if self._world.has_pending_bodies:
            self._world.create_pending_bodies()
        return self._backend.client

    @property
    def is_gui(self) -> bool:
        """Whether a GUI window is open (False after a headless fallback)."""
        return self._backend.is_gui

    @property
    def state(self) -> KinematicState:
        """The state store holding every object's row (for vectorised collaborators)."""
        return self._world.store

    @property
    def fleet(self) -> FleetMotion:
        """Agents' motion: the kinematic engine, action queues and per-agent controllers."""
        return self._fleet

    @property
    def joint_motion(self) -> JointMotion:
        """Moves URDF agents' joints towards their targets each step."""
        return self._joint_motion

    @property
    def world(self) -> World:
        """Objects, rows and attachments (what SimObject handles call back into)."""
        return self._world

    @property
    def attachments(self) -> AttachmentSet:
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
    def sim_objects(self) -> list[SimObject]:
        """Every object, in spawn order."""
        return self._world.objects

    @property
    def agents(self) -> list[SimObject]:
        """Every agent, in spawn order."""
        return self._world.agents

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

    def body_mass(self, body_id: int, link: int = -1) -> float:
        """Mass (kg) PyBullet holds for one link of ``body_id`` (-1: the base); 0.0 for no
        body (-1)."""
        return self._backend.body_mass(body_id, link) if body_id >= 0 else 0.0

    def get_object_by_id(self, object_id: int) -> SimObject | None:
        """The object with ``object_id``, or None."""
        return self._world.get(object_id)

    # ----- objects ------------------------------------------------------------------------

    def add_object(self, obj: SimObject, notify: bool = True) -> None:
        """Register ``obj`` (``SimObject.__init__`` does this when given ``sim_core``).

        Args:
            obj: The object.
            notify: Emit the spawn events now (else ``sim.world.announce(obj)`` does later).

        Raises:
            ValueError: if ``obj`` already belongs to this or another simulation.
        """
        self._world.add(obj, notify)

    def remove_object(self, obj: SimObject) -> None:
        """Remove ``obj`` from the simulation, its managers and PyBullet.

        Objects it carried are detached where they are.

        Raises:
            ValueError: if ``obj`` is not part of this simulation.
        """
        if self._world.get(obj.object_id) is not obj:
            raise ValueError(f"remove_object: {obj!r} is not part of this simulation")
        for manager in list(self._managers):
            manager.remove_object(obj)
        self._world.remove(obj)

    def set_poses(
        self,
        object_ids: Sequence[int],
        positions: np.ndarray,
        orientations: np.ndarray,
        *,
        preserve_velocity: bool = True,
    ) -> None:
        """Set the poses of N objects in one call (arrays of shape (N, 3) and (N, 4)).

        Raises:
            ValueError: on shape mismatch, non-finite values or a zero quaternion.
            KeyError: for an object id that is not registered.
        """
        self._world.set_poses(
            object_ids, positions, orientations, preserve_velocity=preserve_velocity
        )

    def get_poses(self, object_ids: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """Return (positions (N, 3), orientations (N, 4)) copies for N objects.

        Raises:
            KeyError: for an object id that is not registered.
        """
        return self._world.get_poses(object_ids)

    # ----- the step loop ------------------------------------------------------------------

    def step_once(self, return_profiling: bool = False) -> dict[str, float] | None:
        """Run one step (skipped while paused).

        Args:
            return_profiling: Return ``{phase: ms, ..., "total": ms}`` for this step.

        Returns:
            The timings when ``return_profiling`` is set, else None.
        """
        if self._paused:
            return None
        if not self._initialized:
            self.initialize_simulation()
        if self._physics_bodies and self._world.has_pending_bodies:
            self._world.create_pending_bodies()  # dynamics collide with every body
        self._world.in_step = True
        try:
            if return_profiling or self._profiler.log_summary:
                timings = self._profiler.run(self._phases)
            else:
                for _, phase in self._phases:
                    phase()
                self._profiler.discard_custom()
                timings = None
        finally:
            self._world.in_step = False
        return timings if return_profiling else None

    def _phase_pre_step(self) -> None:
        if self.events.has_handlers(SimEvents.PRE_STEP):
            self.events.emit(
                SimEvents.PRE_STEP, sim=self, step=self._step_count, sim_time=self.sim_time
            )

    def _phase_callbacks(self) -> None:
        now, dt = self.sim_time, self._params.timestep
        for callback, elapsed in self._callbacks.due(now, dt):
            callback(self, elapsed)
        for on_step, elapsed in self._plugin_schedule.due(now, dt):
            on_step(elapsed)
        for obj in self._world.objects_with_callbacks():
            obj.execute_callbacks(now)

    def _phase_motion(self) -> None:
        dt = self._params.timestep
        if self.events.has_handlers(SimEvents.PRE_UPDATE):
            self.events.emit(SimEvents.PRE_UPDATE, sim=self, dt=dt)
        for system in tuple(self._motion_systems):
            system.advance(dt)
        for obj in self._world.updaters():
            obj.update(dt)
        if self.events.has_handlers(SimEvents.POST_UPDATE):
            self.events.emit(SimEvents.POST_UPDATE, sim=self, dt=dt)

    def _phase_physics(self) -> None:
        self._backend.sync(self._world.store)
        self._backend.step_physics()
        self._world.read_back_dynamic()

    def _phase_collision(self) -> None:
        if self._collision.is_due(self._step_count, self._params.timestep):
            self._collision.run()

    def _phase_post_step(self) -> None:
        self._step_count += 1
        if self._backend.is_gui:
            self._backend.sync(self._world.store)
        if self.events.has_handlers(SimEvents.POST_STEP):
            self.events.emit(
                SimEvents.POST_STEP, sim=self, step=self._step_count, sim_time=self.sim_time
            )

    # ----- PyBullet's view, profiling -------------------------------------------------------

    def _push_dirty(self, rows: np.ndarray) -> None:
        store = self._world.store
        dirty = rows[store.dirty[rows]]
        if len(dirty):
            self._backend.push_rows(store, dirty)

    def record_profiling(self, name: str, value_ms: float) -> None:
        """Add ``value_ms`` to custom profiling field ``name`` for the current step."""
        self._profiler.record(name, value_ms)

    def get_memory_usage(self) -> dict[str, float] | None:
        """``{"current_mb", "peak_mb"}`` of the Python heap; None unless memory profiling is on."""
        return self._memory.usage()

    def sync_pybullet(self) -> int:
        """Create pending bodies and push every pose PyBullet has not seen yet (before raw
        ``pybullet`` queries); return how many poses were pushed."""
        self._world.create_pending_bodies()
        return self._backend.sync(self._world.store)

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
        for manager in self._managers:
            manager.clear()
        self._backend.reset_world()
        self.rng = np.random.default_rng(self._params.seed if seed is None else seed)
        self.initialize_simulation()
        for obj in removed:
            self.events.emit(SimEvents.OBJECT_REMOVED, sim=self, obj=obj)
        for plugin in self._plugins:
            plugin.on_reset()

    def close(self) -> None:
        """Disconnect from PyBullet; the simulation cannot step afterwards."""
        self._memory.stop()
        self._backend.disconnect()

    def __enter__(self: _Sim) -> _Sim:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ----- rendering ----------------------------------------------------------------------

    def disable_rendering(self) -> None:
        """Stop GUI rendering (for fast spawning)."""
        self._backend.set_rendering(False)

    def enable_rendering(self) -> None:
        """Resume GUI rendering."""
        self._backend.set_rendering(True)

    @contextmanager
    def batch_spawn(self) -> Iterator[None]:
        """Spawn many objects with rendering suspended; rendering is restored afterwards."""
        with self._backend.rendering_disabled():
            yield
