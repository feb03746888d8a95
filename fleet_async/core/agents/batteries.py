"""Every battery of a simulation in one set of arrays, and the one formula of its charge.

A battery's state of charge changes in two ways, and each has exactly one formula:

- *Standing*: a robot that does not move in a step draws ``drain_per_second`` (plus
  ``idle_rate`` when not charging) and gains ``charge_rate`` while charging, at constant
  rates. Such spans are never stepped: the bank keeps each battery's *anchor* (its charge
  ``soc0`` and energy drawn ``used0`` after ``step0`` steps) and evaluates, ``e`` seconds
  (a whole number of steps times ``dt``) later::

      soc  = min(1, max(0, soc0 + (gain - drain) * e))
      used = used0 + min(drain * e, soc0 + gain * e)

  So a span of standing steps gives the same bits whether it was stepped one
  ``step_once()`` at a time, skipped as idle (``sim.skip_steps``), or read half-way.
- *Driving*: a robot whose linear or angular velocity is non-zero in a step draws
  ``drain_per_meter`` per metre (``|v| * dt``) plus ``drain_per_second`` and, when not
  charging, ``discharge_rate`` per second; that step is applied to the anchor (evaluated
  first at the step's start) and the anchor moves to the step's end.

The bank applies the driving steps of all batteries in one numpy pass after the fleet's motion
(``FleetMotion``); ``BatteryPlugin.on_step`` applies the same formula to one battery (the
per-robot reference path, and what a subclass that overrides ``on_step`` runs). Both do the same
IEEE operations in the same order, so they agree to the bit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from fleet_async.core.world.state import KinematicState

__all__ = ["FIELDS", "BatteryBank"]

FIELDS = (
    "soc0",
    "used0",
    "distance",
    "drain_per_meter",
    "drain_per_second",
    "charge_rate",
    "discharge_rate",
    "idle_rate",
)
"""The float fields of a battery (besides ``step0``, ``charging`` and its agent's row)."""


class BatteryBank:
    """Battery slots of one simulation (or of one battery outside any simulation).

    Args:
        clock: Returns the number of steps the batteries are current at (``now``).
        dt: Step length (s).
        store: The state store whose velocities drive the batteries (None: a battery
            outside any simulation, which never drives).
        capacity: Initial number of slots.
        compiled: Drive with the numba kernel (``batteries_jit.py``) instead of numpy.
    """

    def __init__(
        self,
        clock: Callable[[], int],
        dt: float,
        store: KinematicState | None = None,
        capacity: int = 16,
        compiled: bool = False,
    ) -> None:
        self._clock = clock
        self._kernel: Callable[..., bool] | None = None
        if compiled:  # the numba kernel of drive (batteries_jit.py): the same bits
            from fleet_async.core.agents.batteries_jit import drive_batteries

            self._kernel = drive_batteries
        self._store = store
        self.dt = dt
        self.values = {name: np.zeros(capacity) for name in FIELDS}
        self.step0 = np.zeros(capacity, dtype=np.int64)
        self.charging = np.zeros(capacity, dtype=bool)
        self.row = np.full(capacity, -1, dtype=np.int64)
        self.vector = np.zeros(capacity, dtype=bool)  # stepped by the bank's numpy pass
        self._free: list[int] = list(range(capacity - 1, -1, -1))
        self._vector_slots = np.zeros(0, dtype=np.int64)
        self._vector_stale = False
        self._last = 0

    def now(self) -> int:
        """The step count the batteries are evaluated at."""
        now = self._clock()
        if now < self._last:  # the clock restarted (initialize_simulation): rebase anchors
            for slot in np.flatnonzero(self.row >= 0).tolist():
                self.reanchor(slot, self._last)
                self.step0[slot] = now
        self._last = now
        return now

    # ----- slots ---------------------------------------------------------------------------

    def add(
        self, values: dict[str, float], step0: int, charging: bool, row: int, vector: bool
    ) -> int:
        """Take a slot for one battery; return it."""
        if not self._free:
            self._grow()
        slot = self._free.pop()
        for name in FIELDS:
            self.values[name][slot] = values[name]
        self.step0[slot] = step0
        self.charging[slot] = charging
        self.row[slot] = row
        self.vector[slot] = vector
        self._vector_stale = True
        return slot

    def release(self, slot: int) -> None:
        """Give a slot back."""
        self.row[slot] = -1
        self.vector[slot] = False
        self._free.append(slot)
        self._vector_stale = True

    def set_vector(self, slot: int, vector: bool) -> None:
        """Whether the numpy pass steps this battery (else its plugin's ``on_step`` does)."""
        if bool(self.vector[slot]) != vector:
            self.vector[slot] = vector
            self._vector_stale = True

    def snapshot(self, slot: int) -> dict[str, float]:
        """The float fields of one slot."""
        return {name: float(self.values[name][slot]) for name in FIELDS}

    def _grow(self) -> None:
        old = len(self.step0)
        new = 2 * old
        for name in FIELDS:
            self.values[name] = np.concatenate([self.values[name], np.zeros(old)])
        self.step0 = np.concatenate([self.step0, np.zeros(old, dtype=np.int64)])
        self.charging = np.concatenate([self.charging, np.zeros(old, dtype=bool)])
        self.row = np.concatenate([self.row, np.full(old, -1, dtype=np.int64)])
        self.vector = np.concatenate([self.vector, np.zeros(old, dtype=bool)])
        self._free.extend(range(new - 1, old - 1, -1))

    # ----- the standing formula -------------------------------------------------------------

    def rates(self, slot: int) -> tuple[float, float]:
        """(gain, drain) of one battery while standing, SoC per second."""
        v = self.values
        charging = bool(self.charging[slot])
        gain = float(v["charge_rate"][slot]) if charging else 0.0
        drain = float(v["drain_per_second"][slot])
        if not charging:
            drain = drain + float(v["idle_rate"][slot])
        return gain, drain

    def standing(self, slot: int, step: int) -> tuple[float, float]:
        """(soc, used) of one battery after ``step`` steps, standing since its anchor."""
        v = self.values
        soc0, used0 = float(v["soc0"][slot]), float(v["used0"][slot])
        e = (step - int(self.step0[slot])) * self.dt
        gain, drain = self.rates(slot)
        soc = min(1.0, max(0.0, soc0 + (gain - drain) * e))
        return soc, used0 + min(drain * e, soc0 + gain * e)

    def reanchor(self, slot: int, step: int) -> None:
        """Move one battery's anchor to ``step`` (before its rates or charging change)."""
        soc, used = self.standing(slot, step)
        self.values["soc0"][slot] = soc
        self.values["used0"][slot] = used
        self.step0[slot] = step

    # ----- driving steps --------------------------------------------------------------------

    def drive_one(self, slot: int, step: int) -> None:
        """Apply step ``step`` (to ``step + 1``) to one battery, by its robot's velocity in
        the store: the per-robot form of :meth:`drive`."""
        row, store = int(self.row[slot]), self._store
        if row < 0 or store is None:
            return
        vx, vy, vz = (float(c) for c in store.velocity[row])
        speed = math.sqrt(vx * vx + vy * vy + vz * vz)
        if speed == 0.0 and not bool(np.any(store.angular_velocity[row] != 0.0)):
            return  # standing: the anchor's formula covers the step
        soc, used = self.standing(slot, step)
        v, dt = self.values, self.dt
        moved = speed * dt
        charging = bool(self.charging[slot])
        per_second = float(v["drain_per_second"][slot])
        if not charging:
            per_second = per_second + float(v["discharge_rate"][slot])
        drain = float(v["drain_per_meter"][slot]) * moved + per_second * dt
        gain = float(v["charge_rate"][slot]) * dt if charging else 0.0
        v["used0"][slot] = used + min(drain, soc + gain)
        v["soc0"][slot] = min(1.0, max(0.0, soc + (gain - drain)))
        v["distance"][slot] = float(v["distance"][slot]) + moved
        self.step0[slot] = step + 1

    def drive(self, step: int) -> bool:
        """Apply step ``step`` to every bank-stepped battery whose robot moved in it, in one
        numpy pass; return whether any had moved."""
        slots, store = self._vector(), self._store
        if not len(slots) or store is None:
            return False
        if self._kernel is not None:
            values = tuple(self.values[name] for name in FIELDS)
            motion = (store.velocity, store.angular_velocity)
            return self._kernel(
                slots, self.row, motion, self.charging, self.step0, values, step, self.dt
            )
        rows = self.row[slots]
        vel, spin = store.velocity[rows], store.angular_velocity[rows]
        sq = vel[:, 0] * vel[:, 0] + vel[:, 1] * vel[:, 1] + vel[:, 2] * vel[:, 2]
        moving = (sq != 0.0) | (spin != 0.0).any(axis=1)
        if not moving.any():
            return False
        slots, sq = slots[moving], sq[moving]
        v, dt = self.values, self.dt
        charging = self.charging[slots]
        soc0, used0 = v["soc0"][slots], v["used0"][slots]
        e = (step - self.step0[slots]) * dt
        charge = v["charge_rate"][slots]
        stand_gain = np.where(charging, charge, 0.0)
        stand_drain = np.where(
            charging,
            v["drain_per_second"][slots],
            v["drain_per_second"][slots] + v["idle_rate"][slots],
        )
        soc = np.minimum(1.0, np.maximum(0.0, soc0 + (stand_gain - stand_drain) * e))
        used = used0 + np.minimum(stand_drain * e, soc0 + stand_gain * e)
        moved = np.sqrt(sq) * dt
        per_second = np.where(
            charging,
            v["drain_per_second"][slots],
            v["drain_per_second"][slots] + v["discharge_rate"][slots],
        )
        drain = v["drain_per_meter"][slots] * moved + per_second * dt
        gain = np.where(charging, charge * dt, 0.0)
        v["used0"][slots] = used + np.minimum(drain, soc + gain)
        v["soc0"][slots] = np.minimum(1.0, np.maximum(0.0, soc + (gain - drain)))
        v["distance"][slots] = v["distance"][slots] + moved
        self.step0[slots] = step + 1
        return True

    def _vector(self) -> np.ndarray:
        if self._vector_stale:
            self._vector_slots = np.flatnonzero(self.vector)
            self._vector_stale = False
        return self._vector_slots
