"""MultiRobotSimulationCore: the simulation users build, assembled from the layers below.

The kernel (``sim/kernel.py``) owns the clock, the step loop and the objects; the mission seam
(``missions/``) and collision methods (``collision/api.py``) are part of it. This class adds
what stands above the kernel: fleet KPIs (``metrics/``), checkpoints (``checkpoint/``),
scenarios and worlds (``scenario/``), recording, the monitor and the GUI (``view/``), and
``run_simulation``, which wraps the step loop in real-time pacing, the monitor and GUI input.
"""

from __future__ import annotations

from collections.abc import Sequence

from fleet_async.core.base.memory import frozen_heap
from fleet_async.core.base.params import SimulationParams
from fleet_async.core.checkpoint.api import CheckpointApi
from fleet_async.core.maps.api import MapsApi
from fleet_async.core.metrics.kpis import KpiApi
from fleet_async.core.routes.api import RoutesApi
from fleet_async.core.scenario.build import ScenarioApi
from fleet_async.core.scenario.world_loader import WorldLoadingApi
from fleet_async.core.sim.kernel import SimulationKernel
from fleet_async.core.view.gui import GuiApi, handle_keyboard
from fleet_async.core.view.monitor import MonitorApi
from fleet_async.core.view.recording import RecordingApi
from fleet_async.core.view.runner import run_loop
from fleet_async.core.view.trace import TraceApi

__all__ = ["MultiRobotSimulationCore"]


class MultiRobotSimulationCore(
    ScenarioApi,
    WorldLoadingApi,
    RecordingApi,
    TraceApi,
    MonitorApi,
    GuiApi,
    KpiApi,
    RoutesApi,
    MapsApi,
    CheckpointApi,
    SimulationKernel,
):
    """A multi-robot simulation on one PyBullet client.

    Args:
        params: Simulation settings (default ``SimulationParams()``).
        collision_color: RGBA used to highlight colliding objects when
            ``enable_collision_color_change`` is on.
    """

    def __init__(
        self, params: SimulationParams | None = None, collision_color: Sequence[float] | None = None
    ) -> None:
        super().__init__(params, collision_color)
        self.safety.recorder = self.trace_event  # safety stops and deadlocks in the trace
        self.safety.recording = lambda: self.tracer is not None
        self._start_gui_camera()

    def run_simulation(self, duration: float | None = None) -> None:
        """Step for ``duration`` sim seconds (``params.duration`` if None; <= 0 runs until Ctrl+C).

        Paced at ``params.target_rtf`` times real time (0: as fast as possible). A paused
        simulation is resumed first (``RESUMED`` is emitted), as pybullet_fleet does: without a
        GUI nothing could resume it, and the run would never end. Pausing during the run (SPACE
        in the GUI, or ``pause()`` from another thread) holds the clock until ``resume()``.
        """
        if not self._initialized:
            self.initialize_simulation()
        self.resume()
        run_for = self._params.duration if duration is None else duration
        self._frame_gui_camera()
        self.setup_monitor()
        try:
            with frozen_heap(self._params.gc_freeze):
                run_loop(self, float(run_for), idle=self._gui_idle if self.is_gui else None)
        finally:
            self._stop_monitor()
            self._stop_recording_after_run()

    def _gui_idle(self) -> None:
        handle_keyboard(self)

    def reset(self, seed: int | None = None) -> None:
        """Finish a running trace (its clock cannot go back), then reset the kernel; the GUI
        camera frames the new scene at the next step."""
        self.stop_trace()
        super().reset(seed)
        self._frame_gui_camera(restart=True)

    def close(self) -> None:
        """Finish a running trace, stop the monitor and disconnect from PyBullet; the
        simulation cannot step afterwards."""
        self.stop_trace()
        self._stop_monitor()
        super().close()
