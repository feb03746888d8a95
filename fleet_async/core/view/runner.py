"""run_simulation's loop: real-time pacing, the monitor and GUI input wrapped around step_once.

``step_once`` knows nothing of wall-clock time. This module decides how many steps to run before
looking at the clock again, skips the provably empty steps of each batch in spans
(``sim.idle_steps`` / ``sim.skip_steps``: the clock lands exactly where stepping would have
put it, and batches end where they did), sleeps when the simulation is ahead of
``target_rtf`` (so a skipped span is slept through at the paced rate), feeds the monitor,
and polls the GUI keyboard.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

from fleet_async.core.base.steps import steps_for

if TYPE_CHECKING:
    from fleet_async.core.base.params import SimulationParams

__all__ = ["PacedSim", "RealTimePacer", "run_loop", "run_steps"]

logger = logging.getLogger(__name__)


class PacedSim(Protocol):
    """The simulation, as the run loop sees it: the kernel's clock, steps and idle spans, and
    the monitor (``MonitorApi``, beside this module); ``MultiRobotSimulationCore`` has both."""

    @property
    def params(self) -> SimulationParams: ...

    @property
    def step_count(self) -> int: ...

    @property
    def sim_time(self) -> float: ...

    @property
    def is_paused(self) -> bool: ...

    def step_once(self, return_profiling: bool = False) -> dict[str, Any] | None: ...

    def idle_steps(self, limit: int) -> int: ...

    def skip_steps(self, n: int) -> None: ...

    def update_monitor(self) -> None: ...


class RealTimePacer:
    """Keeps sim time at ``target_rtf`` times wall time.

    Args:
        target_rtf: Desired sim seconds per wall second (> 0).
        max_steps_per_frame: Most steps run back to back when catching up.
        clock: Wall clock in seconds (injectable for tests).
        sleep: Sleep function in seconds (injectable for tests).
    """

    def __init__(
        self,
        target_rtf: float,
        max_steps_per_frame: int,
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        if not target_rtf > 0:
            raise ValueError(f"RealTimePacer.target_rtf: expected a number > 0, got {target_rtf!r}")
        self.target_rtf = target_rtf
        self.max_steps_per_frame = max_steps_per_frame
        self._clock = clock
        self._sleep = sleep
        self._wall0 = 0.0
        self._sim0 = 0.0

    def start(self, sim_time: float) -> None:
        """Anchor pacing at the current wall time and ``sim_time``."""
        self._wall0 = self._clock()
        self._sim0 = sim_time

    def steps_now(self, sim_time: float, timestep: float) -> int:
        """Sleep if ahead of schedule; return how many steps to run before checking again."""
        wall_due = (sim_time - self._sim0) / self.target_rtf
        ahead = wall_due - (self._clock() - self._wall0)
        if ahead > 0:
            self._sleep(ahead)
            return 1
        behind_steps = math.floor(-ahead * self.target_rtf / timestep) + 1
        return max(1, min(behind_steps, self.max_steps_per_frame))


def run_steps(sim: PacedSim, steps: int | None, idle: Callable[[], None] | None = None) -> int:
    """Call ``sim.step_once()`` ``steps`` times (forever if None), paced at ``target_rtf``.

    Args:
        sim: The simulation.
        steps: Steps to run, or None to run until interrupted.
        idle: Called once per frame (after each batch of steps, and while paused): GUI
            polling, progress display. It may raise to stop the run.

    Returns:
        Steps run.
    """
    params = sim.params
    start = sim.step_count
    end = None if steps is None else start + steps
    pacer = (
        RealTimePacer(params.target_rtf, params.max_steps_per_frame)
        if params.target_rtf > 0
        else None
    )
    if pacer is not None:
        pacer.start(sim.sim_time)
    while end is None or sim.step_count < end:
        if sim.is_paused:
            if idle is not None:
                idle()
            time.sleep(1.0 / params.gui_min_fps)
            if pacer is not None:
                pacer.start(sim.sim_time)
            continue
        n = (
            pacer.steps_now(sim.sim_time, params.timestep)
            if pacer is not None
            else params.max_steps_per_frame
        )
        if end is not None:
            n = min(n, end - sim.step_count)
        _advance(sim, n)
        sim.update_monitor()
        if idle is not None:
            idle()
    return sim.step_count - start


def _advance(sim: PacedSim, n: int) -> None:
    """Run the frame's ``n`` steps, skipping the empty ones in spans (the frame ends at the
    same step either way, so pacing, the monitor and progress reports see the same frames)."""
    done = 0
    while done < n:
        span = sim.idle_steps(n - done)
        if span:
            sim.skip_steps(span)
            done += span
        else:
            sim.step_once()
            done += 1


def run_loop(sim: PacedSim, duration: float, idle: Callable[[], None] | None = None) -> int:
    """Step ``sim`` for ``duration`` sim seconds (forever if <= 0); return steps run.

    Ctrl+C ends the run quietly (logged), as ``run_simulation`` promises.

    Args:
        sim: The simulation.
        duration: Sim seconds to run: the fewest whole steps that cover it.
        idle: Called once per frame (after each batch of steps and while paused): GUI polling.
    """
    start = sim.step_count
    try:
        run_steps(sim, steps_for(duration, sim.params.timestep) if duration > 0 else None, idle)
    except KeyboardInterrupt:
        logger.info("run_simulation interrupted at sim time %.3f s", sim.sim_time)
    return sim.step_count - start
