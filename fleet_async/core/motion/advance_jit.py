"""The kinematic engine's per-step advance of path-following slots, as one numba kernel.

Imported only when numba is used (``base/compiled.py``). It does what the numpy code of
``KinematicEngine._advance_pose`` does for every moving slot, in one call instead of about
thirty: count the step, sample the trapezoid (``segments.trapezoid_progress``), place the row
on its segment (or on the target in its arrival step), write its velocity and flag it moved.
Every float operation is the numpy code's, in the same order (no fused multiply-add, no fast
math), so positions and velocities are bit-identical. Orientations of turning slots are left
to the numpy code (a slerp's ``sin`` is libm's here and numpy's own there; they may differ in
the last bit), which receives the progress before and after the step.
"""

from __future__ import annotations

import numba
import numpy as np

from fleet_async.core.motion.slots import AT, PROFILE_AT

__all__ = ["advance_translation"]


# Column indices into the slot matrix, frozen into the kernel when it compiles.
def _first(name: str) -> int:
    """Index of the column's first entry in the matrix."""
    place = AT[name]
    return place if isinstance(place, int) else int(place.start)


_U, _STEPS, _T_ARRIVE, _T_END, _THETA = (
    _first(name) for name in ("u", "steps", "t_arrive", "u_t_end", "theta")
)
_PROFILE = int(PROFILE_AT.start)
_P0, _DP, _P1 = (_first(name) for name in ("p0", "dp", "p1"))


@numba.njit(cache=True, nogil=True)
def advance_translation(  # pragma: no cover - compiled; the numpy twin is the reference
    floats: np.ndarray,
    slots: np.ndarray,
    rows: np.ndarray,
    scale: np.ndarray,
    dt: float,
    position: np.ndarray,
    velocity: np.ndarray,
    angular_velocity: np.ndarray,
    dirty: np.ndarray,
    moved: np.ndarray,
    written: np.ndarray,
    arrived: np.ndarray,
    u_old: np.ndarray,
) -> tuple[int, int]:
    """Advance ``slots`` (store ``rows``) by one step of ``dt`` seconds.

    Args:
        floats: The engine's (columns, slots) matrix; ``u`` and ``steps`` are updated.
        slots, rows: The path-following slots and their store rows.
        scale: Per slot, the step's time scale (safety fields); empty for 1.0 everywhere.
        position, velocity, angular_velocity: The store's (N, 3) columns (written; the
            angular velocity of rows that do not turn is zeroed).
        dirty, moved, written: The store's flags (set for ``rows``, as
            ``KinematicState.mark_moved`` sets them).
        arrived, u_old: Filled for the first ``len(slots)`` entries: whether the slot's
            segment ended in this step, and its progress before the step (buffers kept by
            the caller: fresh ones cost page faults at 100,000 slots).

    Returns:
        ``(n_arrived, n_turning)``: how many segments ended and how many slots turn.
    """
    k = len(slots)
    n_arrived = 0
    n_turning = 0
    scaled = len(scale) > 0
    for i in range(k):
        s = slots[i]
        r = rows[i]
        steps = floats[_STEPS, s] + (scale[s] if scaled else 1.0)
        t = steps * dt
        done = t >= floats[_T_ARRIVE, s]
        # segments.trapezoid_progress, term by term
        peak = floats[_PROFILE, s]
        half_peak = floats[_PROFILE + 1, s]
        t_acc = floats[_PROFILE + 2, s]
        divisor = floats[_PROFILE + 3, s]
        half_t_acc = floats[_PROFILE + 4, s]
        t_brake = floats[_PROFILE + 5, s]
        if t < t_acc:
            u = half_peak * t * t / divisor
        elif t > t_brake:
            left = floats[_T_END, s] - t
            if not left >= 0.0:  # np.maximum(left, 0.0), NaN kept
                left = left if left != left else 0.0
            u = 1.0 - half_peak * left * left / divisor
        else:
            u = peak * (t - half_t_acc)
        if u > 1.0:
            u = 1.0
        arrived[i] = done
        if done:
            u = 1.0
            n_arrived += 1
        u_old[i] = floats[_U, s]
        floats[_U, s] = u
        floats[_STEPS, s] = steps
        for a in range(3):
            p = floats[_P1 + a, s] if done else floats[_P0 + a, s] + floats[_DP + a, s] * u
            velocity[r, a] = (p - position[r, a]) / dt
            position[r, a] = p
        if floats[_THETA, s] > 0.0:
            n_turning += 1
        else:
            angular_velocity[r, 0] = 0.0
            angular_velocity[r, 1] = 0.0
            angular_velocity[r, 2] = 0.0
        dirty[r] = True
        moved[r] = True
        written[r] = True
    return n_arrived, n_turning
