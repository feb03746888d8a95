"""SimulationParams: every knob of the simulation, with its default in exactly one place."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path as FsPath
from typing import Any

from fleet_async.core.base.camera_config import CameraConfig, parse_camera_config
from fleet_async.core.base.compiled import KERNEL_MODES
from fleet_async.core.base.config_utils import dataclass_from_dict, load_yaml_config
from fleet_async.core.base.reprs import short_repr
from fleet_async.core.base.types import (
    CollisionDetectionMethod,
    SpatialHashCellSizeMode,
    coerce_enum,
)

__all__ = ["LOG_LEVELS", "SimulationParams"]

LOG_LEVELS = ("debug", "info", "warn", "warning", "error", "critical")


def _require(ok: bool, name: str, value: object, expected: str) -> None:
    if not ok:
        raise ValueError(f"SimulationParams.{name}: expected {expected}, got {short_repr(value)}")


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


@dataclass
class SimulationParams:
    """Simulation configuration.

    Defaults suit headless kinematic simulation, except ``gui=True`` and ``target_rtf=1.0``
    (the reference API's defaults): on a machine without a display ``gui`` falls back to headless
    with one warning. Benchmarks and tests pass ``gui=False, target_rtf=0``.

    Attributes:
        target_rtf: Real-time factor to pace ``run_simulation`` at; 0 runs as fast as possible.
        timestep: Sim seconds per step (> 0).
        duration: Default ``run_simulation`` length in sim seconds (>= 0); 0 runs until
            interrupted. A negative value is refused (``run_simulation(duration=-1)`` keeps the
            seed's "<= 0 runs until interrupted").
        gui: Open the PyBullet GUI (falls back to DIRECT without a display).
        physics: Step PyBullet's dynamics; when False every body is kinematic.
        monitor: Report sim time, real-time factor, objects and collisions while running.
        enable_monitor_gui: Show the monitor in a window where a display exists.
        collision_check_frequency: Hz of sim time; None checks every step, 0 disables.
        log_level: Level of the ``fleet_async`` logger ("debug" ... "critical").
        max_steps_per_frame: Steps run back to back to catch up when pacing falls behind.
        gui_min_fps: Minimum GUI redraw rate while pacing.
        camera_config: What the GUI camera and recordings look at: ``camera_mode`` (auto,
            top_down, orbit, fleet, follow:NAME, manual) and the reference API's other
            ``camera_*`` keys; see ``base/camera_config.py``.
        seed: Seed of the simulation's random generator (``sim.rng``).
        enable_collision_shapes: GUI: draw collision shapes instead of visual ones.
        enable_structure_transparency: GUI: draw static structures (the world) see-through.
        enable_shadows: GUI: draw shadows.
        enable_gui_panel: GUI: show PyBullet's side panel.
        ignore_static_collision: Leave pairs of two static objects out of collision checks.
        enable_time_profiling: Log the time each step phase takes.
        profiling_interval: Steps between two time-profiling reports.
        enable_memory_profiling: Track memory use (tracemalloc) while running.
        enable_collision_color_change: Colour objects red while they collide.
        spatial_hash_cell_size_mode: How the broad phase sizes its cells: "auto_initial"
            (from the objects at the first check), "auto_adaptive" (re-sized as objects come
            and go) or "constant" (``spatial_hash_cell_size``).
        spatial_hash_cell_size: Cell size in metres for the "constant" mode.
        collision_detection_method: Narrow phase: "closest_points", "contact_points" or
            "hybrid"; None picks by ``physics`` when the params are made (contacts with physics
            on, distances without) and the field then holds the method picked, as
            pybullet_fleet's does. ``dataclasses.replace(params, physics=...)`` keeps that
            method: pass ``collision_detection_method=None`` with it to pick again.
        collision_margin: Metres: closer than this counts as touching (closest-points method).
        multi_cell_threshold: Objects larger than this many cells are hashed into every cell
            they cover instead of one.
        enable_floor: Add a floor plane at z = 0.
        camera_config: Initial camera (``camera_mode``, ``camera_view_type``, ...), as
            ``setup_camera`` takes it.
        model_paths: Directories searched first for URDF, mesh and ``model://`` files.
        window_width: GUI window width in pixels.
        window_height: GUI window height in pixels.
        monitor_width: Monitor window width in pixels.
        monitor_height: Monitor window height in pixels.
        monitor_x: Monitor window x position in pixels (-1: placed by the window system).
        monitor_y: Monitor window y position in pixels (-1: placed by the window system).
        sync_pybullet_every_step: Push every pose PyBullet has not seen at the end of each
            step, for scripts that call ``pybullet`` directly on the simulation's bodies. Off
            by default: PyBullet is then synced lazily, when something needs its view (a
            narrow-phase query, a frame, the GUI, physics, ``sim.sync_pybullet()``), and a
            headless kinematic fleet never pays a reset per robot per step.
        collision_sweep: Also report pairs that touched between two checks while neither pair
            of poses touches (each object taken to move on the straight line between its
            positions at the two checks; its orientation is the one at the check). Catches a
            fast robot passing through another within one step; off by default (it costs a
            swept broad phase; see docs/performance.md).
        memory_share: The share of this machine's physical memory a spawn may plan to use
            (> 0; default 0.5). A grid or a scenario whose bodies would need more is refused
            before anything is built, saying how much it needs (at least 16 KiB a body; a
            mobile robot from a URDF takes about 100 KiB). Raise it (e.g. 0.9) to allow more.
        kernels: How the step's hot loops run: "numpy" (the default), "auto" (compiled numba
            kernels when numba is installed, the ``fast`` extra; else numpy) or "numba"
            (required: an ``ImportError`` says how to install it when it is missing). The
            results are the same bit for bit; the kernels pay off in long runs and large
            fleets, while a process's first step with them costs about a second of loading
            (see ``base/compiled.py`` and docs/performance.md, "The bare step at the edge").
        gc_freeze: While ``run_simulation`` or ``fleet_async.run`` runs, keep the objects that
            existed when it started out of the garbage collector's full collections
            (``gc.freeze``, undone when the run ends): at 10,000 robots a full collection
            walks ~400,000 objects, ~120 ms, and this saves about a tenth of a busy step
            (``base/memory.py``). Default True.
    """

    target_rtf: float = 1.0
    timestep: float = 0.1
    duration: float = 0
    gui: bool = True
    physics: bool = False
    monitor: bool = True
    enable_monitor_gui: bool = True
    collision_check_frequency: float | None = None
    log_level: str = "warn"
    max_steps_per_frame: int = 10
    gui_min_fps: int = 30
    enable_collision_shapes: bool = False
    enable_structure_transparency: bool = False
    enable_shadows: bool = True
    enable_gui_panel: bool = False
    ignore_static_collision: bool = True
    enable_time_profiling: bool = False
    profiling_interval: int = 100
    enable_memory_profiling: bool = False
    enable_collision_color_change: bool = False
    spatial_hash_cell_size_mode: SpatialHashCellSizeMode = SpatialHashCellSizeMode.AUTO_INITIAL
    spatial_hash_cell_size: float | None = None
    collision_detection_method: CollisionDetectionMethod | None = None
    collision_margin: float = 0.02
    multi_cell_threshold: float = 1.5
    enable_floor: bool = True
    camera_config: dict[str, Any] | None = None
    model_paths: list[str] | None = None
    window_width: int = 1024
    window_height: int = 768
    monitor_width: int = 200
    monitor_height: int = 290
    monitor_x: int = -1
    monitor_y: int = -1
    seed: int = 0
    sync_pybullet_every_step: bool = False
    collision_sweep: bool = False
    memory_share: float = 0.5
    kernels: str = "numpy"
    gc_freeze: bool = True

    def __post_init__(self) -> None:
        self.spatial_hash_cell_size_mode = coerce_enum(
            SpatialHashCellSizeMode,
            self.spatial_hash_cell_size_mode,
            "SimulationParams.spatial_hash_cell_size_mode",
        )
        if self.collision_detection_method is not None:
            self.collision_detection_method = coerce_enum(
                CollisionDetectionMethod,
                self.collision_detection_method,
                "SimulationParams.collision_detection_method",
            )
        self._validate_numbers()
        self._validate_flags()
        self.collision_detection_method = self.resolved_collision_detection_method
        level = self.log_level.lower() if isinstance(self.log_level, str) else self.log_level
        _require(level in LOG_LEVELS, "log_level", self.log_level, f"one of {LOG_LEVELS}")
        self.log_level = level
        _require(self.kernels in KERNEL_MODES, "kernels", self.kernels, f"one of {KERNEL_MODES}")
        _require(
            self.camera_config is None or isinstance(self.camera_config, dict),
            "camera_config",
            self.camera_config,
            "a mapping or None",
        )
        parse_camera_config(self.camera_config, "SimulationParams.camera_config")
        if self.model_paths is not None:
            _require(
                isinstance(self.model_paths, (list, tuple))
                and all(isinstance(p, (str, FsPath)) for p in self.model_paths),
                "model_paths",
                self.model_paths,
                "a list of directory paths or None",
            )
            self.model_paths = [str(p) for p in self.model_paths]

    def _validate_numbers(self) -> None:
        num = _is_number
        _require(
            num(self.timestep) and self.timestep > 0, "timestep", self.timestep, "a number > 0"
        )
        _require(
            num(self.target_rtf) and self.target_rtf >= 0,
            "target_rtf",
            self.target_rtf,
            "a number >= 0",
        )
        _require(
            num(self.duration) and self.duration >= 0,
            "duration",
            self.duration,
            "a finite number >= 0 (0: run until interrupted)",
        )
        _require(
            num(self.memory_share) and self.memory_share > 0,
            "memory_share",
            self.memory_share,
            "a number > 0 (the share of physical memory a spawn may plan to use)",
        )
        freq = self.collision_check_frequency
        _require(
            freq is None or (num(freq) and freq >= 0),
            "collision_check_frequency",
            freq,
            "None or a number >= 0",
        )
        for name in ("max_steps_per_frame", "gui_min_fps", "profiling_interval"):
            value = getattr(self, name)
            _require(
                isinstance(value, int) and not isinstance(value, bool) and value >= 1,
                name,
                value,
                "an integer >= 1",
            )
        cell = self.spatial_hash_cell_size
        _require(
            cell is None or (num(cell) and cell > 0),
            "spatial_hash_cell_size",
            cell,
            "None or a number > 0",
        )
        _require(
            num(self.collision_margin) and self.collision_margin >= 0,
            "collision_margin",
            self.collision_margin,
            "a number >= 0",
        )
        _require(
            num(self.multi_cell_threshold) and self.multi_cell_threshold > 0,
            "multi_cell_threshold",
            self.multi_cell_threshold,
            "a number > 0",
        )
        for name in ("window_width", "window_height", "monitor_width", "monitor_height"):
            value = getattr(self, name)
            _require(
                isinstance(value, int) and not isinstance(value, bool) and value > 0,
                name,
                value,
                "an integer > 0",
            )
        for name in ("monitor_x", "monitor_y", "seed"):
            value = getattr(self, name)
            _require(
                isinstance(value, int) and not isinstance(value, bool), name, value, "an integer"
            )

    def _validate_flags(self) -> None:
        for f in fields(self):
            if f.type in ("bool", bool):
                value = getattr(self, f.name)
                _require(isinstance(value, bool), f.name, value, "true or false")

    @property
    def camera(self) -> CameraConfig:
        """``camera_config`` checked and parsed (``base/camera_config.py``)."""
        return parse_camera_config(self.camera_config, "SimulationParams.camera_config")

    @property
    def resolved_collision_detection_method(self) -> CollisionDetectionMethod:
        """The narrow-phase method in force: ``collision_detection_method``, else (if it was
        set to None after the params were made) the one ``physics`` picks."""
        if self.collision_detection_method is not None:
            return self.collision_detection_method
        if self.physics:
            return CollisionDetectionMethod.CONTACT_POINTS
        return CollisionDetectionMethod.CLOSEST_POINTS

    @classmethod
    def from_dict(cls, config: dict[str, Any], *, source: str | None = None) -> SimulationParams:
        """Build params from a mapping of field names (a YAML ``simulation:`` section).

        Raises:
            ValueError: for an unknown key (naming it, the nearest valid key and ``source``), or
                a bad value (naming the field and the value).
        """
        return dataclass_from_dict(cls, config, source=source, section="simulation")

    @classmethod
    def from_config(cls, config_path: str = "config.yaml") -> SimulationParams:
        """Load params from a YAML file: its ``simulation:`` section, or the whole file if flat.

        Raises:
            FileNotFoundError: if ``config_path`` does not exist.
            ValueError: for malformed YAML or bad keys/values, naming the file.
        """
        config = load_yaml_config(config_path)
        section = config.get("simulation", config) if isinstance(config, dict) else config
        if section is None:
            section = {}
        if not isinstance(section, dict):
            raise ValueError(f"{config_path}: 'simulation' must be a mapping, got {section!r}")
        return cls.from_dict(section, source=str(config_path))
