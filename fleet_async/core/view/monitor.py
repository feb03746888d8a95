"""DataMonitor: live simulation figures in a small window, or in the log when headless.

The window runs in a child process (``python -m fleet_async.core.view.monitor_window``) fed JSON
lines on its stdin, so a slow or closed window never blocks the simulation. Where there is no
display, or tkinter is missing, the same figures go to the ``fleet_async.core.view.monitor`` logger
at INFO level.
"""

from __future__ import annotations

import importlib.util
import json
import logging
import subprocess
import sys
import time
from collections import deque
from typing import TYPE_CHECKING, Any

from fleet_async.core.world.backend import display_available

if TYPE_CHECKING:
    from fleet_async.core.base.params import SimulationParams
    from fleet_async.core.bodies.sim_object import SimObject
    from fleet_async.core.world.world import World

__all__ = ["DataMonitor", "MonitorApi", "SimulationMonitor"]

logger = logging.getLogger(__name__)


class DataMonitor:
    """Show simulation statistics.

    Args:
        title: Window title.
        enable_gui: Open a window where a display and tkinter exist.
        width: Window width in pixels.
        height: Window height in pixels.
        x: Window x position (-1 lets the window manager choose).
        y: Window y position (-1 lets the window manager choose).
    """

    def __init__(
        self,
        title: str = "Simulation Monitor",
        enable_gui: bool = True,
        width: int = 200,
        height: int = 290,
        x: int = -1,
        y: int = -1,
    ) -> None:
        self.title = title
        self.enable_gui = enable_gui
        self.geometry = (width, height, x, y)
        self._proc: subprocess.Popen[str] | None = None
        self._running = False

    @property
    def uses_window(self) -> bool:
        """Whether figures go to a window (True) or to the log (False)."""
        return self._proc is not None

    @staticmethod
    def window_possible() -> bool:
        """Whether a monitor window could be opened on this machine."""
        return display_available() and importlib.util.find_spec("tkinter") is not None

    def start(self) -> None:
        """Open the window (if enabled and possible); otherwise report to the log."""
        if self._running:
            return
        self._running = True
        if not (self.enable_gui and self.window_possible()):
            logger.info("%s: no window (headless); figures go to this log", self.title)
            return
        width, height, x, y = self.geometry
        cmd = [
            sys.executable,
            "-m",
            "fleet_async.core.view.monitor_window",
            self.title,
            str(width),
            str(height),
            str(x),
            str(y),
        ]
        try:
            self._proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, text=True)
        except OSError as exc:
            logger.warning(
                "%s: could not open the monitor window (%s); using the log", self.title, exc
            )
            self._proc = None

    def stop(self) -> None:
        """Close the window, if any."""
        self._running = False
        if self._proc is not None:
            try:
                if self._proc.stdin:
                    self._proc.stdin.close()
                self._proc.wait(timeout=2.0)
            except (OSError, subprocess.TimeoutExpired):
                self._proc.kill()
            self._proc = None

    def write_data(self, sim_data: dict[str, Any]) -> None:
        """Show one set of figures (a flat mapping of name to value)."""
        if self._proc is not None and self._proc.poll() is None and self._proc.stdin:
            try:
                self._proc.stdin.write(json.dumps(sim_data, default=str) + "\n")
                self._proc.stdin.flush()
                return
            except OSError:
                self._proc = None
        logger.info("%s: %s", self.title, ", ".join(f"{k}={_fmt(v)}" for k, v in sim_data.items()))


def _fmt(value: Any) -> str:
    return f"{value:.3f}" if isinstance(value, float) else str(value)


class SimulationMonitor:
    """Samples a simulation's figures about once per wall-clock second for a DataMonitor.

    The real-time factor is sim time over wall time across a sliding window of 10 s.
    """

    def __init__(self, monitor: DataMonitor, window_s: float = 10.0, period_s: float = 1.0) -> None:
        self.monitor = monitor
        self._window_s = window_s
        self._period_s = period_s
        self._samples: deque[tuple[float, float]] = deque()
        self._last_write = -float("inf")

    def figures(
        self, sim_time: float, step_count: int, objects: int, agents: int, collisions: int
    ) -> dict[str, Any]:
        """Record a sample and return the figures it yields."""
        now = time.perf_counter()
        self._samples.append((now, sim_time))
        while len(self._samples) > 2 and now - self._samples[0][0] > self._window_s:
            self._samples.popleft()
        (w0, s0), (w1, s1) = self._samples[0], self._samples[-1]
        rtf = (s1 - s0) / (w1 - w0) if w1 > w0 else 0.0
        return {
            "sim_time": sim_time,
            "real_time_factor": rtf,
            "steps": step_count,
            "objects": objects,
            "agents": agents,
            "collisions": collisions,
        }

    def update(
        self, sim_time: float, step_count: int, objects: int, agents: int, collisions: int
    ) -> bool:
        """Sample, and write to the monitor if a period has passed; return whether it wrote."""
        data = self.figures(sim_time, step_count, objects, agents, collisions)
        now = self._samples[-1][0]
        if now - self._last_write < self._period_s:
            return False
        self._last_write = now
        self.monitor.write_data(data)
        return True


class MonitorApi:
    """The simulation's monitor (mixed into MultiRobotSimulationCore): started by
    ``run_simulation`` when ``params.monitor`` is on, fed by the run loop, stopped after it."""

    _monitor: SimulationMonitor | None = None

    # Provided by the simulation kernel.
    params: SimulationParams
    sim_time: float
    step_count: int
    world: World[SimObject]
    collision_count: int

    def setup_monitor(self) -> None:
        """Start the DataMonitor if ``params.monitor`` is on (window only with a display)."""
        if not self.params.monitor or self._monitor is not None:
            return
        prm = self.params
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
                self.step_count,
                self.world.object_count,
                self.world.agent_count,
                self.collision_count,
            )

    def _stop_monitor(self) -> None:
        if self._monitor is not None:
            self._monitor.monitor.stop()
            self._monitor = None
