"""Velocity-command motion of the kinematic engine: body-frame commands within the limits.

A slot in velocity mode follows a body-frame command (vx, vy, vz in m/s, wz in rad/s). Each
step its velocity moves toward the command by at most the acceleration limits times ``dt``,
clipped to the velocity limits, and the body covers the step's *mean* velocity, so a start
from rest moves ``a * dt^2 / 2`` as the acceleration limit allows. Yaw turns about world z
(a ground robot); the linear velocity is rotated by the yaw at the middle of the step.
"""

from __future__ import annotations

import math

import numpy as np

from fleet_async.core.geometry.quaternions import yaw_from_quats
from fleet_async.core.world.state import KinematicState

__all__ = ["advance_velocity", "body_velocity"]


def body_velocity(store: KinematicState, row: int) -> tuple[float, float, float, float]:
    """A row's current motion as a body-frame command (vx, vy, vz, wz): where a new command
    ramps from, so switching to velocity mode stays within the acceleration limits."""
    yaw = float(yaw_from_quats(store.orientation[row][None, :])[0])
    vx, vy, vz = store.velocity[row]
    cos, sin = math.cos(yaw), math.sin(yaw)
    return (cos * vx + sin * vy, -sin * vx + cos * vy, vz, store.angular_velocity[row][2])


def advance_velocity(
    store: KinematicState,
    rows: np.ndarray,
    old: np.ndarray,
    command: np.ndarray,
    limits: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    dt: float,
) -> np.ndarray:
    """Move ``rows`` by one step of ``dt`` seconds toward their body-frame commands.

    Args:
        store: The state store; the rows' pose and velocities are written.
        rows: Store rows, one per moving slot.
        old: ``(n, 4)`` body-frame velocities (vx, vy, vz, wz) the previous step left.
        command: ``(n, 4)`` body-frame commands.
        limits: ``(vmax, amax, wmax, alpha)``, each ``(n, 3)``; only z of the angular ones
            applies.
        dt: Step length (s).

    Returns:
        The ``(n, 4)`` body-frame velocities at the end of the step.
    """
    vmax, amax, wmax, alpha = limits
    acc = np.concatenate([amax, alpha[:, 2:3]], axis=1) * dt
    cap = np.concatenate([vmax, wmax[:, 2:3]], axis=1)
    vel = old + np.clip(command - old, -acc, acc)
    vel = np.clip(vel, -cap, cap)
    mean = 0.5 * (old + vel)
    yaw = yaw_from_quats(store.orientation.take(rows, axis=0))
    mid = yaw + 0.5 * mean[:, 3] * dt
    cos, sin = np.cos(mid), np.sin(mid)
    world = np.stack(
        [cos * mean[:, 0] - sin * mean[:, 1], sin * mean[:, 0] + cos * mean[:, 1], mean[:, 2]],
        axis=1,
    )
    store.position[rows] += world * dt
    new_yaw = yaw + mean[:, 3] * dt
    half = 0.5 * new_yaw
    store.orientation[rows] = np.stack(
        [np.zeros_like(half), np.zeros_like(half), np.sin(half), np.cos(half)], axis=1
    )
    store.velocity[rows] = world
    store.angular_velocity[rows] = np.stack(
        [np.zeros_like(yaw), np.zeros_like(yaw), mean[:, 3]], axis=1
    )
    moving = np.any(vel != 0.0, axis=1) | np.any(old != 0.0, axis=1)
    if moving.any():
        store.mark_moved(rows[moving])
    return vel
