"""The trace's event log: actions, collisions, removals and user events, stamped with steps.

The log listens on the simulation's event bus (actions) and to the collision system (one call
per check with its lists of pairs that ended and started) while a trace runs, keeps what it
hears in Python lists and hands it to the writer as EVENTS and COLLISIONS records when the writer
flushes (before the FRAMES record that shows their step). It also keeps the set of bodies
whose last action failed, for the frames' FLAG_FAILED bit.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Callable
from itertools import chain
from typing import TYPE_CHECKING, Any

import numpy as np

from fleet_async.core.base.events import SimEvents
from fleet_async.core.view.trace_format import RecordKind

if TYPE_CHECKING:
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["TraceEventLog", "json_bytes"]

Record = tuple[RecordKind, list[Any]]
"""A record to write: its kind and the payload's parts (bytes-like), in order."""


def json_bytes(value: Any) -> bytes:
    """Compact UTF-8 JSON of a record payload (values that are not JSON become their str)."""
    return json.dumps(value, separators=(",", ":"), default=str, allow_nan=False).encode()


class TraceEventLog:
    """What happened during a traced run, between two flushes of the writer.

    Args:
        sim: The traced simulation.
    """

    def __init__(self, sim: MultiRobotSimulationCore) -> None:
        self._sim = sim
        self._events: list[list[Any]] = []
        # Collisions arrive by the hundred per step at fleet scale: the collision system hands
        # over each check's lists of pairs in one call, and they become arrays at flush time.
        self._collisions: list[tuple[int, list[tuple[int, int]], list[tuple[int, int]]]] = []
        self._failed: set[int] = set()
        self.flag_version = 0
        """Bumped whenever the set of failed bodies changes (the writer caches flag masks)."""
        self._handlers: list[tuple[str, Callable[..., Any]]] = [
            (SimEvents.ACTION_STARTED, self._on_action_started),
            (SimEvents.ACTION_COMPLETED, self._on_action_ended),
            (SimEvents.ACTION_FAILED, self._on_action_ended),
        ]

    @property
    def failed(self) -> set[int]:
        """Object ids whose last action failed."""
        return self._failed

    def hook(self) -> None:
        """Start listening; pairs already touching start, for the trace, in its first frame."""
        sim = self._sim
        active = sim.get_active_collision_pairs()
        if active:
            self._collisions.append((sim.step_count, [], active))
        for event, handler in self._handlers:
            sim.events.on(event, handler)
        sim.add_collision_listener(self._on_collisions)

    def unhook(self) -> None:
        """Stop listening."""
        for event, handler in self._handlers:
            self._sim.events.off(event, handler)
        self._sim.remove_collision_listener(self._on_collisions)

    # ----- stamps -------------------------------------------------------------------------

    def step_stamp(self) -> int:
        """The frame that shows what happens now: inside ``step_once``, the step's end."""
        return self._sim.step_count + (1 if self._sim.in_step else 0)

    def _now(self) -> float:
        return self.step_stamp() * self._sim.params.timestep

    # ----- events -------------------------------------------------------------------------

    def event(self, kind: str, object_id: int | None = None, **data: Any) -> None:
        """Add an event (``sim.trace_event`` lands here); see ``TraceWriter.event``."""
        self._events.append([self._now(), self.step_stamp(), str(kind), object_id, data])

    def note_removed(self, obj: Any) -> None:
        """``obj`` is leaving the simulation: log it and forget its failed state."""
        if obj.object_id in self._failed:
            self._failed.discard(obj.object_id)
            self.flag_version += 1
        self.event("removed", obj.object_id)

    def _on_action_started(self, agent: Any, action: Any, **_: Any) -> None:
        if agent.object_id in self._failed:
            self._failed.discard(agent.object_id)
            self.flag_version += 1
        t = action.start_time if action.start_time is not None else self._now()
        data = {"action": type(action).__name__}
        self._events.append([t, self.step_stamp(), "action_started", agent.object_id, data])

    def _on_action_ended(self, agent: Any, action: Any, **_: Any) -> None:
        status = getattr(action.status, "value", str(action.status))
        if status == "failed":
            self._failed.add(agent.object_id)
            self.flag_version += 1
        t = action.end_time if action.end_time is not None else self._now()
        data: dict[str, Any] = {"action": type(action).__name__, "status": status}
        if action.error_message:
            data["reason"] = action.error_message
        self._events.append([t, self.step_stamp(), "action_ended", agent.object_id, data])

    # ----- collisions -----------------------------------------------------------------------

    def _on_collisions(self, ended: list[tuple[int, int]], started: list[tuple[int, int]]) -> None:
        self._collisions.append((self.step_stamp(), ended, started))

    # ----- records ------------------------------------------------------------------------

    def drain(self) -> list[Record]:
        """The EVENTS and COLLISIONS records of everything logged since the last drain."""
        records: list[Record] = []
        if self._events:
            records.append((RecordKind.EVENTS, [json_bytes({"events": self._events})]))
            self._events = []
        if self._collisions:
            records.append((RecordKind.COLLISIONS, self._collision_parts()))
            self._collisions = []
        return records

    def _collision_parts(self) -> list[Any]:
        """A COLLISIONS payload: pairs that ended or started (in that order per check), with
        the step of the frame that shows each."""
        lists = [pairs for _, ended, started in self._collisions for pairs in (ended, started)]
        counts = np.fromiter(map(len, lists), dtype=np.int64, count=len(lists))
        total = int(counts.sum())
        stamps = np.fromiter((s for s, _, _ in self._collisions), dtype=np.int32)
        ids = np.fromiter(
            chain.from_iterable(chain.from_iterable(lists)), dtype=np.int32, count=2 * total
        ).reshape(-1, 2)
        return [
            struct.pack("<I", total),
            np.repeat(np.repeat(stamps, 2), counts).tobytes(),
            np.ascontiguousarray(ids[:, 0]).tobytes(),
            np.ascontiguousarray(ids[:, 1]).tobytes(),
            np.repeat(np.tile(np.array([0, 1], dtype=np.uint8), len(stamps)), counts).tobytes(),
        ]
