"""The simulation's checkpoint methods, ``save_state`` and ``restore_state``.

Mixed into ``MultiRobotSimulationCore`` (``core/simulation.py``), above the kernel: they hand
the kernel's clock and collaborators to ``saving.py`` / ``restoring.py`` and set the clock back
after a restore.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, cast

from fleet_async.core.checkpoint.format import CheckpointParts
from fleet_async.core.checkpoint.restoring import restore
from fleet_async.core.checkpoint.saving import save

if TYPE_CHECKING:
    from fleet_async.core.agents.fleet import FleetMotion
    from fleet_async.core.base.scheduling import PeriodicSchedule
    from fleet_async.core.collision.system import CollisionSystem
    from fleet_async.core.motion.joints import JointMotion
    from fleet_async.core.sim.kernel import MotionSystem, SimulationKernel

__all__ = ["CheckpointApi"]


class CheckpointApi:
    """``save_state`` / ``restore_state`` of a kinematic simulation (mixed into the simulation)."""

    # Provided by the simulation kernel.
    _step_count: int
    _collision_count: int
    _paused: bool
    _initialized: bool
    _fleet: FleetMotion
    _callbacks: PeriodicSchedule
    _plugin_schedule: PeriodicSchedule
    _collision: CollisionSystem
    _joint_motion: JointMotion
    _motion_systems: list[MotionSystem]

    def save_state(self, path: str | os.PathLike[str]) -> None:
        """Write a checkpoint of this kinematic simulation to ``path`` (between steps).

        ``restore_state`` on a simulation built from the same scenario, in any process,
        continues from it step for step identically. Missions, physics, added motion systems
        (devices) and per-object callbacks are not captured: see ``fleet_async.core.checkpoint``.

        Raises:
            CheckpointError: naming what cannot be saved (also while ``fleet_async.run`` is in
                progress: a mission waiting mid-await cannot be saved).
        """
        save(cast("SimulationKernel", self), path, self._checkpoint_parts())

    def restore_state(self, path: str | os.PathLike[str], *, unsafe: bool = False) -> None:
        """Bring this simulation, freshly built from the scenario a checkpoint was saved from
        and not stepped yet, to the state ``save_state`` wrote to ``path``.

        Everything is checked before anything changes: a refused checkpoint leaves the
        simulation as it was. Reading a checkpoint runs no code from it.

        Args:
            path: The checkpoint file.
            unsafe: Also read a format-1 checkpoint, a pickle, which runs any code it names:
                only for a file whose maker you trust (then save it again, in format 2).

        Raises:
            CheckpointError: for a simulation built differently or already stepped, naming
                the difference; for a file that is no checkpoint or a pickle without
                ``unsafe``, naming the file.
        """
        sim = cast("SimulationKernel", self)
        clock = restore(sim, path, self._checkpoint_parts(), unsafe)
        self._step_count, self._collision_count, self._paused = clock
        self._initialized = True  # step_once must not zero the restored clock

    def _checkpoint_parts(self) -> CheckpointParts:
        return CheckpointParts(
            self._step_count,
            self._collision_count,
            self._paused,
            self._fleet.engine,
            self._fleet.actions,
            self._callbacks,
            self._plugin_schedule,
            self._collision,
            self._joint_motion,
            tuple(
                system
                for system in self._motion_systems
                if system is not self._fleet and system is not self._joint_motion
            ),
        )
