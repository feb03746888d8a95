"""Many one-waypoint paths started at once: the kinematic engine's batch of goals.

A patrol or a random walk sends its agent one goal at a time, and in a fleet many of them do so
in the same step (patrols that started together keep arriving together: at 10,000 robots a
third of the fleet starts in one step). The fleet hands such goals over in one call
(``ControllerSchedule``), and what ``KinematicEngine.set_path(slot, [goal])`` does for each (a
plan, then its first segment) is done here with numpy for every goal that starts a plain
straight segment: an idle omnidirectional slot with scalar limits, a goal at least ``EPS_LEN``
away, and an orientation whose squared norm is 1 to the bit (so the segment does not turn; the
turn to the goal's orientation follows on arrival, as it does one by one). The arithmetic is
``KinematicEngine._start``'s, operation for operation and in its order, so the columns hold the
same bits; ``tests/core/test_goal_starts.py`` compares them. Any other goal starts one by one,
as do all of a batch too small to pay for its numpy calls (fewer than ``BATCH_MIN``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.motion.segments import EPS_LEN, PROFILE_TERMS
from fleet_async.core.motion.slots import AT, POSE, SlotTable
from fleet_async.core.world.state import KinematicState

__all__ = ["BATCH_MIN", "GoalStarts"]

BATCH_MIN = 16
"""Goals below which a batch starts them one by one: its few dozen numpy calls cost more."""


class GoalStarts(SlotTable):
    """``start_goals``: the batch version of ``set_path(slot, [goal])`` (a base of the engine)."""

    _store: KinematicState
    _plans: list

    def _plan_goal(self, slot: int, goal: Pose, direction: object) -> None:
        """Give ``slot`` the plan of the path ``[goal]`` with its segment under way."""
        raise NotImplementedError

    def set_path(
        self, slot: int, waypoints: Sequence[Pose], direction: Any, final_orientation_align: bool
    ) -> None:
        """Follow ``waypoints`` (the engine's own, one slot at a time)."""
        raise NotImplementedError

    def start_goals(
        self, slots: Sequence[int], goals: Sequence[Pose], directions: Sequence[Any]
    ) -> None:
        """``set_path(slots[k], [goals[k]], directions[k], True)`` for every k, in one batch.

        The goals the batch does not take start one by one after it; a start calls back only
        when the path ends at once (a goal where the robot stands and turned as it is), and
        then only the slot's own agent learns of it, so the order does not matter."""
        if len(slots) < BATCH_MIN:
            for slot, goal, direction in zip(slots, goals, directions, strict=True):
                self.set_path(slot, (goal,), direction, True)
            return
        s = np.asarray(slots, dtype=np.int64)
        rows = self.row[s]
        p = self._store.position[rows]
        q = self._store.orientation[rows]
        t = np.array([g.position for g in goals], dtype=float).reshape(len(goals), 3)
        d = t - p
        length = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])
        # _start's dot of the orientation with itself, summed in its order
        dot = q[:, 0] * q[:, 0] + q[:, 1] * q[:, 1] + q[:, 2] * q[:, 2] + q[:, 3] * q[:, 3]
        vmax, amax = self.vmax[s, 0], self.amax[s, 0]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            rate_v, rate_a = vmax / length, amax / length
            peak = np.minimum(rate_v, np.sqrt(rate_a))
            t_acc = peak / rate_a
            t_end = t_acc + 1.0 / peak
        plans = self._plans
        simple = (
            (self.kind[s] == 0)  # KIND_OMNI
            & self.lin_scalar[s]
            & (self.mode[s] != POSE)
            & np.fromiter((plans[k] is None for k in slots), bool, len(s))
            & (dot >= 1.0)  # min(dot, 1.0) == 1.0: no turn (acos(1.0) is 0.0)
            & (length >= EPS_LEN)
            & np.isfinite(amax)
            & np.isfinite(peak)
            & (t_acc > 0.0)
            & np.isfinite(t_end)
        )
        take = simple.nonzero()[0]
        if len(take):
            self._write_straight(
                s[take], p[take], q[take], t[take], d[take], peak[take], t_acc[take], t_end[take]
            )
            for k in take.tolist():
                self._plan_goal(slots[k], goals[k], directions[k])
            self.mode[s[take]] = POSE
            self._moving = None
        for k in (~simple).nonzero()[0].tolist():
            self.set_path(slots[k], (goals[k],), directions[k], True)

    def _write_straight(
        self,
        s: np.ndarray,
        p: np.ndarray,
        q: np.ndarray,
        t: np.ndarray,
        d: np.ndarray,
        peak: np.ndarray,
        t_acc: np.ndarray,
        t_end: np.ndarray,
    ) -> None:
        """Write the segment columns of straight, non-turning segments (``_start``'s values)."""
        m = self.segment_matrix(len(s))
        m[AT["t_arrive"]] = t_end - 1e-9
        m[AT["u_t_end"]] = t_end
        terms = (peak, 0.5 * peak, t_acc, t_acc, 0.5 * t_acc, t_end - t_acc)
        for name, value in zip(PROFILE_TERMS, terms, strict=True):
            m[AT[name]] = value
        m[AT["p0"]] = p.T
        m[AT["dp"]] = d.T
        m[AT["p1"]] = t.T
        m[AT["q0"]] = q.T
        m[AT["q1"]] = q.T  # the orientation kept: q1 = q0, and the goal orientation too
        m[AT["q_goal"]] = q.T
        m[AT["sl_dot"]] = 1.0  # theta, axis, sl_theta, sl_sin stay 0.0: no turn
        m[AT["u_peak"]] = peak
        m[AT["u_t_acc"]] = t_acc
        self.write_segments(s, m)
