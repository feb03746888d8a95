"""One step of the path-following slots: numpy passes, or one compiled kernel.

The base of the kinematic engine (``kinematics.py``) that moves every slot in POSE mode along
its segment by one step: progress from the trapezoid (``segments.trapezoid_progress``),
position on the segment (the target in the arrival step), velocity, and the slerped
orientation of segments that rotate. With ``SimulationParams.kernels`` resolving to numba
(``base/compiled.py``) everything but the slerp runs in ``advance_jit.advance_translation``;
the results are the same bit for bit (``tests/core/test_compiled.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from fleet_async.core.geometry.quaternions import quat_slerp_batch
from fleet_async.core.motion.segments import trapezoid_progress
from fleet_async.core.motion.slots import AT, PROFILE_AT, SlotTable
from fleet_async.core.world.state import KinematicState

__all__ = ["PoseAdvance"]

_NO_SCALE = np.empty(0)


class PoseAdvance(SlotTable):
    """Per-step integration of POSE-mode slots (the kinematic engine's base)."""

    _store: KinematicState
    _kernel: Callable[..., Any] | None = None  # advance_jit.advance_translation, when used
    _u_old = np.empty(0)  # the kernel's output buffers (grown per engine)
    _arrived_buf = np.empty(0, dtype=bool)

    def _use_kernel(self, compiled: bool) -> None:
        """Run the advance as the numba kernel (``compiled``) or as numpy passes."""
        if compiled:
            from fleet_async.core.motion.advance_jit import advance_translation

            self._kernel = advance_translation
        else:
            self._kernel = None

    def _arrived(self, slots: np.ndarray) -> None:
        """Plan the next segment of ``slots``, whose segments ended this step."""
        raise NotImplementedError

    def _advance_pose(self, s: np.ndarray, rows: np.ndarray, flat: np.ndarray, dt: float) -> None:
        """Advance the POSE-mode slots ``s`` (store ``rows``, their ``flat`` indices)."""
        if self._kernel is not None:
            store = self._store
            k = len(s)
            if len(self._u_old) < k:
                self._u_old = np.empty(2 * k)
                self._arrived_buf = np.empty(2 * k, dtype=bool)
            arrived, u_old = self._arrived_buf[:k], self._u_old[:k]
            n_arrived, n_turning = self._kernel(
                self._floats,
                s,
                rows,
                _NO_SCALE if self._scale is None else self._scale,
                dt,
                store.position,
                store.velocity,
                store.angular_velocity,
                store.dirty,
                store.moved,
                store.written,
                arrived,
                u_old,
            )
            if n_turning:
                t = (self.theta[s] > 0.0).nonzero()[0]
                st = s[t]
                self._turn(st, rows[t], self.u[st], u_old[t], arrived[t], dt)
            if n_arrived:
                self._arrived(s[arrived])  # s[arrived] copies: the buffer may be reused
            return
        self._advance_numpy(s, rows, flat, dt)

    def _advance_numpy(self, s: np.ndarray, rows: np.ndarray, flat: np.ndarray, dt: float) -> None:
        # One gather of the float columns a step reads (see slots.py); a 100-robot step is a
        # few dozen numpy calls, so each one saved counts.
        f = self._move_block.take(s, axis=1)  # (columns, slots): f[AT[name]] is one column
        store = self._store
        steps = f[AT["steps"]] + (1.0 if self._scale is None else self._scale[s])
        # The step in which the profile's end falls is the arrival step (t_arrive: t_end less
        # the float error of k * dt, so that 14 steps of 0.1 s cover a 1.4 s segment).
        elapsed = steps * dt
        arrived = elapsed >= f[AT["t_arrive"]]
        any_arrived = bool(np.count_nonzero(arrived))
        u_new = trapezoid_progress(elapsed, f[PROFILE_AT], f[AT["u_t_end"]])
        if any_arrived:
            u_new[arrived] = 1.0
        u_old = f[AT["u"]]
        self.u[s] = u_new
        self.steps[s] = steps
        # Positions as (3, slots), read and written through the rows' flat indices.
        position = store.position.reshape(-1)
        pos = f[AT["p0"]] + f[AT["dp"]] * u_new
        if any_arrived:
            pos[:, arrived] = f[AT["p1"]][:, arrived]
        store.velocity.reshape(-1)[flat] = (pos - position[flat]) / dt
        position[flat] = pos
        # Orientation work only for segments that rotate (pure translations keep theirs).
        turning = f[AT["theta"]] > 0.0
        if not np.count_nonzero(turning):
            store.angular_velocity.reshape(-1)[flat] = 0.0
        else:
            t = turning.nonzero()[0]
            if len(t) < len(rows):
                store.angular_velocity[rows] = 0.0
            self._turn(s[t], rows[t], u_new[t], u_old[t], arrived[t], dt)
        store.mark_moved(rows)
        if any_arrived:
            self._arrived(s[arrived])

    def _turn(
        self,
        st: np.ndarray,
        r: np.ndarray,
        un: np.ndarray,
        uo: np.ndarray,
        done: np.ndarray,
        dt: float,
    ) -> None:
        """Orientation and angular velocity of the turning slots ``st`` (store rows ``r``),
        at progress ``un`` (``uo`` before the step); ``done``: arrived this step."""
        store = self._store
        ft = self._turn_block.take(st, axis=1)
        quat = quat_slerp_batch(
            ft[AT["q0"]].T,
            ft[AT["q1"]].T,
            un,
            ft[AT["sl_dot"]],
            ft[AT["sl_theta"]],
            ft[AT["sl_sin"]],
        )
        if np.count_nonzero(done):
            quat[done] = ft[AT["q_goal"]].T[done]
        store.orientation[r] = quat
        rate = (un - uo) * ft[AT["theta"]] / dt
        store.angular_velocity[r] = ft[AT["axis"]].T * rate[:, None]
