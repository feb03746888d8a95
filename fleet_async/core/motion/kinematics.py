"""Vectorised kinematic motion for every agent on a built-in (omni / differential) controller.

Each agent on a built-in controller owns one *slot* of this engine. A slot follows its path one
*segment* at a time; a segment moves the body from a start pose to a target pose along a
straight line while slerping its orientation, both driven by one normalised progress
``u`` in [0, 1] that follows a trapezoidal velocity profile. The profile's limits are chosen per
segment so that neither the linear (m/s, m/s^2) nor the angular (rad/s, rad/s^2) limits are
exceeded:

    du/dt    <= min(v_max_along / L, w_max_about / theta)
    d2u/dt2  <= min(a_max_along / L, alpha_max_about / theta)

Each step samples the exact profile ``u(t)`` (``segments.trapezoid_progress``) at the step's
end, ``t = k * dt`` for the k-th step of the segment: the body starts moving in the step the
segment starts, never moves further in a step than the limits allow from the state the
previous step left, and lands exactly on the target in the step in which ``t`` reaches the
profile's duration (2 m at 2 m/s and 5 m/s^2: 1.4 s, 14 steps of 0.1 s).

A differential robot's path becomes ROTATE segments (L = 0, turn to face the next waypoint) and
FORWARD segments (theta = 0, drive straight). An omnidirectional robot drives every leg at its
current orientation; with ``final_orientation_align`` both end with a turn in place to the last
waypoint's orientation. Every segment starts and ends at rest and ends exactly on its target.

``advance(dt)`` integrates all moving slots with numpy in one pass (velocity commands through
``velocity.py``). Python runs only when a segment ends (to plan the next one), never per robot
per step; one-waypoint paths that start in the same step (the goals of patrols and random
walks) start together (``start_goals``, ``goal_starts.py``). ``get_state`` / ``set_state``
hand every slot's columns and path to a checkpoint.
"""

from __future__ import annotations

import heapq
import math
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fleet_async.core.base.types import MovementDirection
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.quaternions import quat_from_euler, yaw_from_quats
from fleet_async.core.motion.advance import PoseAdvance
from fleet_async.core.motion.goal_starts import GoalStarts
from fleet_async.core.motion.segments import (
    EPS_ANGLE,
    EPS_LEN,
    MotionLimits,
    as_floats,
    heading_toward,
    profile_terms,
    segment_rates,
    trapezoid_duration,
)
from fleet_async.core.motion.slots import (
    COLUMNS,
    IDLE,
    POSE,
    VELOCITY,
    flat_rows,
)
from fleet_async.core.motion.velocity import advance_velocity, body_velocity
from fleet_async.core.world.state import KinematicState

__all__ = ["KIND_DIFFERENTIAL", "KIND_OMNI", "KinematicEngine"]

KIND_OMNI = 0
KIND_DIFFERENTIAL = 1
_NONE, _TURNED, _DRIVING = 0, 1, 2  # progress toward the plan's next waypoint


@dataclass
class _Plan:
    waypoints: deque[Pose]
    direction: MovementDirection
    final_align: bool
    final_orientation: np.ndarray
    total: int
    stage: int = _NONE
    aligned: bool = False


class KinematicEngine(GoalStarts, PoseAdvance):
    """Moves every slot's row of the state store by its path or velocity command.

    Args:
        store: The simulation's state store.
        on_motion_end: Called ``(slot, reached)`` when a slot stops: ``reached`` is True when it
            finished its path, False when stopped or replaced.
        compiled: Advance path-following slots with the numba kernel (``advance.py``).
    """

    def __init__(
        self,
        store: KinematicState,
        on_motion_end: Callable[[int, bool], None],
        compiled: bool = False,
    ) -> None:
        self._store = store
        self._on_motion_end = on_motion_end
        self._free: list[int] = []
        self._stopped: list[int] = []  # slots that arrived last step: zero their velocity next
        self._plans: list[_Plan | None] = []
        super().__init__()
        self._alloc(16)
        self._use_kernel(compiled)

    # ----- slots --------------------------------------------------------------------------

    def _alloc(self, cap: int) -> None:
        super()._alloc(cap)
        self._plans.extend([None] * (cap - len(self._plans)))

    def add(self, row: int, kind: int, limits: MotionLimits) -> int:
        """Give a store row a slot; return the slot index."""
        if self._free:
            slot = heapq.heappop(self._free)
        else:
            slot = self._high
            self._high += 1
            if slot >= len(self.row):
                self._alloc(2 * len(self.row))
        self.row[slot] = row
        self.kind[slot] = kind
        self._set_mode(slot, IDLE)
        self.cmd[slot] = 0.0  # a reused slot starts without its last owner's command
        self.vel[slot] = 0.0
        self.set_limits(slot, limits)
        self._plans[slot] = None
        return slot

    def remove(self, slot: int) -> None:
        """Free a slot (no motion-end callback)."""
        self._set_mode(slot, IDLE)
        self.row[slot] = -1
        self._plans[slot] = None
        heapq.heappush(self._free, slot)

    def set_limits(self, slot: int, limits: MotionLimits) -> None:
        """Replace a slot's kinematic limits (applies from the next segment)."""
        # Called once per spawned agent: plain assignments, no temporary arrays.
        self.vmax[slot] = limits.max_linear_vel
        self.amax[slot] = limits.max_linear_accel
        self.wmax[slot] = limits.max_angular_vel
        self.alpha[slot] = limits.max_angular_accel
        self.lin_scalar[slot] = isinstance(limits.max_linear_vel, float)
        self.ang_scalar[slot] = isinstance(limits.max_angular_vel, float)

    # ----- checkpoints ----------------------------------------------------------------------

    def get_state(self) -> dict[str, Any]:
        """Every slot's motion: columns, paths, free slots (for ``sim.save_state``)."""
        high = self._high
        return {
            "high": high,
            "free": sorted(self._free),
            "stopped": list(self._stopped),
            "plans": list(self._plans[:high]),
            "columns": {name: getattr(self, name)[:high].copy() for name in COLUMNS},
        }

    def check_state(self, state: dict[str, Any]) -> None:
        """Check, changing nothing, that :meth:`set_state` can take ``state``.

        Raises:
            ValueError: if the slots hold other rows (a simulation built differently).
        """
        high = state["high"]
        rows = state["columns"]["row"]
        if high != self._high or not np.array_equal(rows, self.row[:high]):
            raise ValueError(
                f"the checkpoint's motion slots ({high}) drive other objects than this "
                f"simulation's ({self._high}): build it from the same scenario"
            )
        for name, values in state["columns"].items():
            column = getattr(self, name, None) if name in COLUMNS else None
            if column is None or np.shape(values)[1:] != column.shape[1:] or len(values) != high:
                raise ValueError(f"the checkpoint's motion column {name!r} does not fit")

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore :meth:`get_state` onto an engine whose slots hold the same store rows.

        Raises:
            ValueError: if the slots hold other rows (a simulation built differently).
        """
        self.check_state(state)
        high = state["high"]
        for name, values in state["columns"].items():
            getattr(self, name)[:high] = values
        for slot in range(high):
            self._derive(slot)
        self._moving = None
        self._free = list(state["free"])
        heapq.heapify(self._free)
        self._stopped = list(state["stopped"])
        self._plans[:high] = list(state["plans"])

    # ----- queries ------------------------------------------------------------------------

    def is_idle(self) -> bool:
        """Whether ``advance`` would change nothing (no motion, no arrival left to settle)."""
        if self._stopped:
            return False
        pose, _, _, vel = self._moving_slots()
        return not (len(pose) or len(vel))

    def is_moving(self, slot: int) -> bool:
        """Whether the slot follows a path or a non-zero velocity command."""
        mode = self.mode[slot]
        if mode == POSE:
            return True
        return bool(
            mode == VELOCITY
            and (np.count_nonzero(self.vel[slot]) or np.count_nonzero(self.cmd[slot]))
        )

    def moving_mask(self, slots: np.ndarray) -> np.ndarray:
        """Whether each of ``slots`` is moving: :meth:`is_moving` for many slots at once."""
        mode = self.mode[slots]
        moving = mode == POSE
        velocity = mode == VELOCITY
        if velocity.any():  # rare: the velocity columns only for slots under a command
            s = slots[velocity]
            moving[velocity] = self.vel[s].any(axis=1) | self.cmd[s].any(axis=1)
        return moving

    def remaining_waypoints(self, slot: int) -> list[Pose]:
        """Waypoints not reached yet (the current target first)."""
        plan = self._plans[slot]
        return [] if plan is None else list(plan.waypoints)

    def waypoint_index(self, slot: int) -> int:
        """Index of the waypoint being approached in the path given to ``set_path``."""
        plan = self._plans[slot]
        if plan is None:
            return 0
        return min(plan.total - len(plan.waypoints), max(plan.total - 1, 0))

    def goal(self, slot: int) -> Pose | None:
        """The final pose of the current path, or None when idle."""
        plan = self._plans[slot]
        if plan is None:
            return None
        position = plan.waypoints[-1].position if plan.waypoints else self.p1[slot]
        return Pose.from_arrays_unchecked(position.copy(), plan.final_orientation.copy())

    # ----- commands -----------------------------------------------------------------------

    def set_path(
        self,
        slot: int,
        waypoints: Sequence[Pose],
        direction: MovementDirection,
        final_orientation_align: bool,
    ) -> None:
        """Follow ``waypoints`` from the current pose (replacing any motion in progress)."""
        self._interrupt(slot)
        wps = deque(waypoints)
        if not wps:
            self._finish(slot, reached=True)
            return
        self._plans[slot] = _Plan(
            waypoints=wps,
            direction=direction,
            final_align=final_orientation_align,
            final_orientation=wps[-1].orientation.copy(),
            total=len(wps),
        )
        self._set_mode(slot, POSE)
        self._plan_next(slot)

    def _plan_goal(self, slot: int, goal: Pose, direction: object) -> None:
        """The plan ``set_path(slot, [goal])`` leaves once its straight segment started
        (``start_goals``)."""
        assert isinstance(direction, MovementDirection)
        self._plans[slot] = _Plan(
            waypoints=deque((goal,)),
            direction=direction,
            final_align=True,
            final_orientation=goal.orientation.copy(),
            total=1,
            stage=_DRIVING,
        )

    def set_velocity(self, slot: int, command: Sequence[float]) -> None:
        """Follow a body-frame velocity command (vx, vy, vz in m/s, wz in rad/s)."""
        if self.mode[slot] == POSE:
            self._interrupt(slot)
        if self.mode[slot] != VELOCITY:
            # Start from the current motion so the command ramps within the accel limits.
            self.vel[slot] = body_velocity(self._store, int(self.row[slot]))
        self.cmd[slot] = command
        self._set_mode(slot, VELOCITY)

    def stop(self, slot: int) -> None:
        """Stop at once: no path, no command, zero velocity."""
        self._interrupt(slot)
        self._set_mode(slot, IDLE)
        self.cmd[slot] = 0.0
        self.vel[slot] = 0.0
        row = self.row[slot]
        self._store.velocity[row] = 0.0
        self._store.angular_velocity[row] = 0.0

    def _interrupt(self, slot: int) -> None:
        """End a path in progress without reaching it (motion-end callback, reached=False)."""
        if self._plans[slot] is not None or self.mode[slot] == POSE:
            self._plans[slot] = None
            self._set_mode(slot, IDLE)
            self._on_motion_end(slot, False)

    # ----- planning (Python, once per segment) ---------------------------------------------

    def _plan_next(self, slot: int) -> None:
        """Start the slot's next segment, or finish its path."""
        plan = self._plans[slot]
        assert plan is not None
        row = self.row.item(slot)
        store = self._store
        # The pose as Python floats, read once: no segment start writes the store.
        here = (store.position[row].tolist(), store.orientation[row].tolist())
        differential = self.kind.item(slot) == KIND_DIFFERENTIAL
        while True:
            if plan.stage == _DRIVING:  # the segment to waypoints[0] has just ended
                plan.waypoints.popleft()
                plan.stage = _NONE
            if plan.waypoints:
                target = plan.waypoints[0]
                if differential and plan.stage == _NONE:
                    plan.stage = _TURNED
                    pos, orn = store.position[row], store.orientation[row]
                    heading = heading_toward(plan.direction, pos, orn, target.position)
                    if heading is not None and self._start(slot, here, pos, heading):
                        return
                    continue
                plan.stage = _DRIVING
                # Drive at the current orientation; the final one is reached by the turn below.
                if self._start(slot, here, target.position, here[1]):
                    return
                continue
            if plan.final_align and not plan.aligned:
                plan.aligned = True
                final = plan.final_orientation
                if differential:  # a ground robot aligns its heading only
                    final = quat_from_euler(0.0, 0.0, float(yaw_from_quats(final[None, :])[0]))
                if self._start(slot, here, here[0], final):
                    return
                continue
            self._finish(slot, reached=True)
            return

    def _start(
        self,
        slot: int,
        here: tuple[list[float], list[float]],
        target_pos: np.ndarray | list[float],
        target_orn: np.ndarray | list[float],
    ) -> bool:
        """Begin a segment from ``here`` (the slot's position and orientation) to (target_pos,
        target_orn); False if there is nothing to do. Runs once per segment for one slot, so
        it works on Python floats: small numpy calls would cost more than the arithmetic."""
        (px, py, pz), (ax, ay, az, aw) = here
        tx, ty, tz = as_floats(target_pos)
        goal = as_floats(target_orn)  # the orientation on arrival
        bx, by, bz, bw = goal
        dx, dy, dz = tx - px, ty - py, tz - pz
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        dot = ax * bx + ay * by + az * bz + aw * bw
        if dot < 0.0:  # shortest path: q and -q are the same rotation
            bx, by, bz, bw, dot = -bx, -by, -bz, -bw, -dot
        dot = min(dot, 1.0)
        sl_theta = math.acos(dot)
        theta = 2.0 * sl_theta  # rotation angle between the two orientations
        if length < EPS_LEN and theta < EPS_ANGLE:
            self.q_goal[slot] = goal
            return False
        rate_v, rate_a = math.inf, math.inf
        if length >= EPS_LEN:
            unit = (dx / length, dy / length, dz / length)
            rate_v, rate_a = segment_rates(
                self.vmax[slot], self.amax[slot], self.lin_scalar.item(slot), unit, length
            )
        axis = (0.0, 0.0, 0.0)
        if theta >= EPS_ANGLE:
            # relative rotation q1 * conj(q0); its vector part is the axis times sin(theta / 2)
            rx = bw * -ax + bx * aw + by * -az - bz * -ay
            ry = bw * -ay - bx * -az + by * aw + bz * -ax
            rz = bw * -az + bx * -ay - by * -ax + bz * aw
            sin_half = math.sqrt(rx * rx + ry * ry + rz * rz)
            axis = (
                (rx / sin_half, ry / sin_half, rz / sin_half) if sin_half > 0 else (0.0, 0.0, 1.0)
            )
            turn_v, turn_a = segment_rates(
                self.wmax[slot], self.alpha[slot], self.ang_scalar.item(slot), axis, theta
            )
            rate_v, rate_a = min(rate_v, turn_v), min(rate_a, turn_a)
        peak, t_acc, t_end = trapezoid_duration(rate_v, rate_a)
        # In SEGMENT_COLUMNS' order; dp, the profile's terms and t_arrive as _derive has them.
        self.write_segment(
            slot,
            [
                *(0.0, 0.0, t_end - 1e-9, t_end),  # u, steps, t_arrive, u_t_end
                *profile_terms(peak, t_acc, t_end),
                *(px, py, pz, dx, dy, dz, tx, ty, tz, theta),  # p0, dp, p1, theta
                *(ax, ay, az, aw, bx, by, bz, bw),  # q0, q1
                *goal,  # q_goal
                *axis,
                *(dot, sl_theta, math.sin(sl_theta), peak, t_acc),
            ],
        )
        self._set_mode(slot, POSE)
        return True

    def _finish(self, slot: int, reached: bool) -> None:
        # The velocity of the step that arrived stays visible for that step; it is zeroed at
        # the start of the next advance unless a new segment is under way by then.
        self._plans[slot] = None
        self._set_mode(slot, IDLE)
        self._stopped.append(slot)
        self._on_motion_end(slot, reached)

    # ----- integration (numpy, every step) --------------------------------------------------

    def advance(self, dt: float) -> None:
        """Move every slot by one step of ``dt`` seconds."""
        if self._high == 0:
            return
        if self._stopped:
            idle = [s for s in self._stopped if self.mode[s] == IDLE and self.row[s] >= 0]
            self._stopped.clear()
            if idle:
                rows = self.row[idle]
                self._store.velocity[rows] = 0.0
                self._store.angular_velocity[rows] = 0.0
        pose_slots, pose_rows, flat, vel_slots = self._moving_slots()
        if len(pose_slots):
            self._advance_pose(pose_slots, pose_rows, flat, dt)
            # Arrivals ran callbacks (action completion, events) that may have changed modes
            # or removed agents: take the velocity slots as they are now.
            vel_slots = self._moving_slots()[3]
        if len(vel_slots):
            self._advance_velocity(vel_slots, dt)

    def advance_slot(self, slot: int, dt: float) -> None:
        """Move one slot by ``dt`` seconds (an agent advanced on its own, outside a step)."""
        if slot in self._stopped:
            self._stopped.remove(slot)
            if self.mode[slot] == IDLE:
                self._store.velocity[self.row[slot]] = 0.0
                self._store.angular_velocity[self.row[slot]] = 0.0
        if self.mode[slot] == POSE:
            rows = self.row[slot : slot + 1]
            self._advance_pose(np.array([slot]), rows, flat_rows(rows), dt)
        elif self.mode[slot] == VELOCITY:
            self._advance_velocity(np.array([slot]), dt)

    def _arrived(self, slots: np.ndarray) -> None:
        plans, mode, kind, row = self._plans, self.mode, self.kind, self.row
        orientation = self._store.orientation
        for slot in slots.tolist():
            plan = plans[slot]
            if plan is None or mode[slot] != POSE:
                continue
            if (
                plan.stage == _DRIVING
                and len(plan.waypoints) == 1
                and plan.final_align
                and not plan.aligned
                and kind[slot] == KIND_OMNI
            ):
                # How _plan_next ends an omni path whose final turn is none: _start finds the
                # quaternions' |dot| at 1 (no angle) and nothing to drive, and the path ends.
                goal = plan.final_orientation.tolist()
                ax, ay, az, aw = orientation[row[slot]].tolist()
                bx, by, bz, bw = goal
                dot = ax * bx + ay * by + az * bz + aw * bw
                if dot >= 1.0 or dot <= -1.0:
                    plan.waypoints.popleft()
                    plan.stage = _NONE
                    plan.aligned = True
                    self.q_goal[slot] = goal
                    self._finish(slot, reached=True)
                    continue
            self._plan_next(slot)

    def _advance_velocity(self, s: np.ndarray, dt: float) -> None:
        limits = (self.vmax[s], self.amax[s], self.wmax[s], self.alpha[s])
        cmd = self.cmd[s]
        if self._scale is not None:  # safety fields: 0 stops at once, < 1 caps the command
            scale = self._scale[s]
            self.vel[s[scale <= 0.0]] = 0.0
            cmd = cmd * scale[:, None]
        self.vel[s] = advance_velocity(self._store, self.row[s], self.vel[s], cmd, limits, dt)
