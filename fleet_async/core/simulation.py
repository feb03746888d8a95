"""MultiRobotSimulationCore: the step loop and the objects it moves.

The step loop is the only clock: ``sim_time == step_count * timestep``. One step runs these
phases in order, each a call into the module that owns it:

1. ``events_pre_step``  - PRE_STEP event.
2. ``callbacks``        - simulation callbacks, plugins and per-object callbacks that are due.
3. ``agent_update``     - PRE_UPDATE, motion systems and overridden ``update(dt)``, POST_UPDATE.
4. ``attachments``      - attached objects follow their parent links.
5. ``step_simulation``  - PyBullet dynamics (only present when ``physics=True``).
6. ``events_post_step`` - the clock advances, the GUI is synced, POST_STEP event.

Profiling (``return_profiling``), real-time pacing and the monitor wrap this loop
(``profiling.py``, ``runner.py``, ``monitor.py``); they are not branches inside it.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, Protocol

import numpy as np
import pybullet as p

from fleet_async.core import gui
from fleet_async.core.attachments import AttachmentSet
from fleet_async.core.backend import PyBulletBackend
from fleet_async.core.collision import CollisionSystem
from fleet_async.core.events import SimEvents
from fleet_async.core.fleet import FleetMotion
from fleet_async.core.joints import JointMotion
from fleet_async.core.mission_api import SimEventBus, SimMissionApi
from fleet_async.core.monitor import DataMonitor, SimulationMonitor
from fleet_async.core.params import SimulationParams
from fleet_async.core.plugins import SimPlugin
from fleet_async.core.profiling import MemoryProfiler, StepProfiler
from fleet_async.core.recording import RecordingApi
from fleet_async.core.runner import run_loop
from fleet_async.core.scenario import ScenarioApi
from fleet_async.core.scheduling import PeriodicSchedule
from fleet_async.core.sim_object import SimObject
from fleet_async.core.state import KinematicState
from fleet_async.core.trace import TraceApi
from fleet_async.core.types import SpatialHashCellSizeMode, coerce_enum
from fleet_async.core.world import World
from fleet_async.core.world_loader import WorldLoadingApi

__all__ = ["MotionSystem", "MultiRobotSimulationCore"]

logger = logging.getLogger(__name__)

_LOG_LEVELS = {"debug": 10, "info": 20, "warn": 30, "warning": 30, "error": 40, "critical": 50}


class MotionSystem(Protocol):
    """Something that advances many objects per step (e.g. a vectorised controller)."""

    def advance(self, dt: float) -> None:
        """Move every object this system owns by one step of ``dt`` seconds."""


class MultiRobotSimulationCore(SimMissionApi, ScenarioApi, WorldLoadingApi, RecordingApi, TraceApi):
    """A multi-robot simulation on one PyBullet client.

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
        self._world = World(self, self._backend, self.events, self._params.physics)
        self._fleet = FleetMotion(self)
        self._collision = CollisionSystem(self, self._push_dirty)
        self._callbacks = PeriodicSchedule()
        self._plugin_schedule = PeriodicSchedule()
        self._plugins: list[SimPlugin] = []
        self._managers: list[Any] = []
        self._joint_motion = JointMotion(self._fleet.wake_action)
        self._motion_systems: list[MotionSystem] = [self._fleet, self._joint_motion]
        self._step_count = 0
        self._collision_count = 0
        self._paused = False
        self._initialized = False
        self._profiler = StepProfiler(
            self._params.profiling_interval, self._params.enable_time_profiling
        )
        self._memory = MemoryProfiler(self._params.enable_memory_profiling)
        self._monitor: SimulationMonitor | None = None
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
        """PyBullet physics client id, for raw ``pybullet`` calls (``physicsClientId=``)."""
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
    def collision_count(self) -> int:
        """Collisions that started since the last ``initialize_simulation``."""
        return self._collision_count

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

    # ----- callbacks, plugins, managers, motion systems -----------------------------------

    def register_callback(
        self,
        callback: Callable[[MultiRobotSimulationCore, float], Any],
        frequency: float | None = None,
    ) -> None:
        """Call ``callback(sim, dt)`` every step (None) or at ``frequency`` Hz of sim time."""
        self._callbacks.add(callback, frequency, owner="register_callback")

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
        if isinstance(plugin_or_cls, type) and issubclass(plugin_or_cls, SimPlugin):
            plugin = plugin_or_cls(self, config)
        elif isinstance(plugin_or_cls, SimPlugin):
            if config is not None:
                raise ValueError(
                    "register_plugin: config applies to a plugin class, not an instance"
                )
            plugin = plugin_or_cls
        else:
            raise TypeError(
                "register_plugin: expected a SimPlugin or SimPlugin subclass, "
                f"got {plugin_or_cls!r}"
            )
        freq = frequency if frequency is not None else plugin.frequency
        self._plugin_schedule.add(
            plugin.on_step, freq, owner=f"register_plugin({type(plugin).__name__})"
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
            self._collision.check()

    def _phase_post_step(self) -> None:
        self._step_count += 1
        if self._backend.is_gui:
            self._backend.sync(self._world.store)
        if self.events.has_handlers(SimEvents.POST_STEP):
            self.events.emit(
                SimEvents.POST_STEP, sim=self, step=self._step_count, sim_time=self.sim_time
            )

    # ----- collisions -----------------------------------------------------------------------

    def _push_dirty(self, rows: np.ndarray) -> None:
        store = self._world.store
        dirty = rows[store.dirty[rows]]
        if len(dirty):
            self._backend.push_rows(store, dirty)

    def note_collisions(self, started: int) -> None:
        """Count collisions that started (called by the collision system)."""
        self._collision_count += started

    def get_aabbs(self) -> dict[int, tuple[list[float], list[float]]]:
        """``{object_id: (aabb_min, aabb_max)}`` of every object taking part in collisions."""
        return self._collision.get_aabbs()

    def filter_aabb_pairs(
        self,
        ignore_static: bool | None = None,
        moved_objects: set[int] | None = None,
        return_profiling: bool = False,
    ) -> tuple[list[tuple[int, int]], dict[str, float] | None]:
        """Broad phase only: object-id pairs whose AABBs overlap and involve a moved object.

        Args:
            ignore_static: Skip pairs with a STATIC object (default: params).
            moved_objects: Object ids to treat as moved (default: those that moved).
            return_profiling: Also return ``{get_aabbs, spatial_hashing, aabb_filtering,
                total}`` in ms.
        """
        t0 = time.perf_counter()
        rows, timings = self._collision.filter_pairs(ignore_static, moved_objects)
        ids = self._world.store.object_id[rows].tolist() if len(rows) else []
        pairs = sorted(tuple(sorted(pair)) for pair in ids)
        timings["total"] = (time.perf_counter() - t0) * 1e3
        return pairs, timings if return_profiling else None

    def check_collisions(
        self,
        collision_color: list[float] | None = None,
        ignore_static: bool | None = None,
        return_profiling: bool = False,
    ) -> tuple[list[tuple[int, int]], dict[str, float] | None]:
        """Run a collision check now; return the active pairs (object ids, i < j)."""
        pairs, timings = self._collision.check(ignore_static, collision_color)
        return pairs, timings if return_profiling else None

    def get_active_collision_pairs(self) -> list[tuple[int, int]]:
        """Pairs (object_id_i < object_id_j) in contact as of the last check."""
        return self._collision.active_pairs()

    def set_collision_check_frequency(self, frequency: float | None = None) -> None:
        """Check every step (None), never (0), or at ``frequency`` Hz of sim time."""
        self._collision.set_frequency(frequency)

    def set_collision_spatial_hash_cell_size_mode(
        self, mode: SpatialHashCellSizeMode | str | None = None, cell_size: float | None = None
    ) -> float:
        """Switch the hash cell size mode (CONSTANT needs ``cell_size``) and recompute it.

        Returns:
            The cell size now in force (m, > 0).
        """
        if mode is not None:
            self._collision.cell_mode = coerce_enum(SpatialHashCellSizeMode, mode, "mode")
        if cell_size is not None:
            if not (isinstance(cell_size, (int, float)) and cell_size > 0):
                raise ValueError(f"cell_size: expected a number > 0 (m), got {cell_size!r}")
            self._collision.cell_size = float(cell_size)
        elif (
            self._collision.cell_mode is SpatialHashCellSizeMode.CONSTANT
            and not self._collision.cell_size
        ):
            raise ValueError(
                "set_collision_spatial_hash_cell_size_mode: CONSTANT mode needs a cell_size"
            )
        rows = self._collision.prepare_rows()
        if self._collision.cell_mode is SpatialHashCellSizeMode.CONSTANT:
            return float(self._collision.cell_size or 1.0)
        return self._collision.resolve_cell_size(rows, recompute=True)

    def record_profiling(self, name: str, value_ms: float) -> None:
        """Add ``value_ms`` to custom profiling field ``name`` for the current step."""
        self._profiler.record(name, value_ms)

    def get_memory_usage(self) -> dict[str, float] | None:
        """``{"current_mb", "peak_mb"}`` of the Python heap; None unless memory profiling is on."""
        return self._memory.usage()

    def sync_pybullet(self) -> int:
        """Push every pose PyBullet has not seen yet (before raw ``pybullet`` queries)."""
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

    def run_simulation(self, duration: float | None = None) -> None:
        """Step for ``duration`` sim seconds (``params.duration`` if None; <= 0 runs until Ctrl+C).

        Paced at ``params.target_rtf`` times real time (0: as fast as possible).
        """
        if not self._initialized:
            self.initialize_simulation()
        run_for = self._params.duration if duration is None else duration
        self.setup_monitor()
        try:
            run_loop(self, float(run_for), idle=self._gui_idle if self.is_gui else None)
        finally:
            if self._monitor is not None:
                self._monitor.monitor.stop()
                self._monitor = None
            self._stop_recording_after_run()

    def _gui_idle(self) -> None:
        gui.handle_keyboard(self)

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
        generator is reseeded with ``seed``, or with ``params.seed``. A running trace is
        finished first (its clock cannot go back).
        """
        self.stop_trace()
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
        """Finish a running trace and disconnect from PyBullet; the simulation cannot step
        afterwards."""
        self.stop_trace()
        if self._monitor is not None:
            self._monitor.monitor.stop()
            self._monitor = None
        self._memory.stop()
        self._backend.disconnect()

    def __enter__(self) -> MultiRobotSimulationCore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ----- monitor, rendering, camera -----------------------------------------------------

    def setup_monitor(self) -> None:
        """Start the DataMonitor if ``params.monitor`` is on (window only with a display)."""
        if not self._params.monitor or self._monitor is not None:
            return
        prm = self._params
        monitor = DataMonitor(
            enable_gui=prm.enable_monitor_gui,
            width=prm.monitor_width,
            height=prm.monitor_height,
            x=prm.monitor_x,
            y=prm.monitor_y,
        )
        monitor.start()
        self._monitor = SimulationMonitor(monitor)

    def update_monitor(self) -> None:
        """Send the current figures to the monitor (about once per wall second)."""
        if self._monitor is not None:
            self._monitor.update(
                self.sim_time,
                self._step_count,
                self._world.object_count,
                self._world.agent_count,
                self._collision_count,
            )

    def setup_pybullet(self) -> None:
        """Hide the GUI side panels (no-op headless)."""
        if self.is_gui:
            p.configureDebugVisualizer(
                p.COV_ENABLE_GUI, int(self._params.enable_gui_panel), physicsClientId=self.client
            )

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

    def configure_visualizer(
        self, enable_structure_transparency: bool | None = None, enable_shadows: bool | None = None
    ) -> None:
        """Apply visualizer flags (defaults from params; no-op headless)."""
        if not self.is_gui:
            return
        prm = self._params
        gui.configure_visualizer(
            self.client,
            prm.enable_structure_transparency
            if enable_structure_transparency is None
            else enable_structure_transparency,
            prm.enable_shadows if enable_shadows is None else enable_shadows,
            prm.enable_collision_shapes,
        )

    def compute_scene_bounds(self) -> tuple[list[float], list[float]]:
        """(center, extent) of all object positions; zeros when empty."""
        store = self._world.store
        return gui.scene_bounds(store.position[store.live_rows()])

    def setup_camera(
        self,
        camera_config: dict[str, Any] | None = None,
        entity_positions: Sequence[Sequence[float]] | None = None,
    ) -> tuple[float, float, float, list[float]]:
        """Frame the camera on the scene or ``entity_positions``.

        Returns:
            (distance, yaw, pitch, target) of the view.

        The view is computed headless too (recorders use it); it is applied only with a GUI.
        """
        if entity_positions is not None:
            center, extent = gui.scene_bounds(
                np.asarray(entity_positions, dtype=float).reshape(-1, 3)
            )
        else:
            center, extent = self.compute_scene_bounds()
        view = gui.camera_view(
            camera_config if camera_config is not None else self._params.camera_config,
            center,
            extent,
        )
        if self.is_gui:
            distance, yaw, pitch, target = view
            p.resetDebugVisualizerCamera(distance, yaw, pitch, target, physicsClientId=self.client)
        return view
