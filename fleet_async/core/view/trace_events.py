"""The trace's event log: actions, collisions, removals and user events, stamped with steps.

The log listens on the simulation's event bus while a trace runs, keeps what it hears in
Python lists and hands it to the writer as EVENTS and COLLISIONS records when the writer
flushes (before the FRAMES record that shows their step). It also keeps the set of bodies
whose last action failed, for the frames' FLAG_FAILED bit.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Callable
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
        # Collision events arrive by the hundred per step at fleet scale, so their handlers
        # only append the two objects; ids and steps are resolved in bulk when flushing.
        self._collided: list[list[Any]] = [[], []]  # [ended objects, started objects] (pairs)
        self._collision_marks: list[tuple[int, int, int]] = []  # (step, ended len, started len)
        self._collision_rows: list[tuple[list[int], list[int], list[int]]] = []  # resolved
        self._failed: set[int] = set()
        self.flag_version = 0
        """Bumped whenever the set of failed bodies changes (the writer caches flag masks)."""
        self._handlers: list[tuple[str, Callable[..., Any]]] = [
            (SimEvents.ACTION_STARTED, self._on_action_started),
            (SimEvents.ACTION_COMPLETED, self._on_action_ended),
            (SimEvents.ACTION_FAILED, self._on_action_ended),
            (SimEvents.COLLISION_STARTED, self._on_collision_started),
            (SimEvents.COLLISION_ENDED, self._on_collision_ended),
        ]

    @property
    def failed(self) -> set[int]:
        """Object ids whose last action failed."""
        return self._failed

    def hook(self) -> None:
        """Start listening; pairs already touching start, for the trace, in its first frame."""
        sim = self._sim
        for a, b in sim.get_active_collision_pairs():
            self._collided[1] += (sim.get_object_by_id(a), sim.get_object_by_id(b))
        for event, handler in self._handlers:
            sim.events.on(event, handler)

    def unhook(self) -> None:
        """Stop listening."""
        for event, handler in self._handlers:
            self._sim.events.off(event, handler)

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
        # Pending collision events hold objects; resolve their ids while this one has its id.
        self.mark(self.step_stamp())
        self._resolve_collisions()
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

    # The simulation bus's collision payload is (sim, obj_a, obj_b); naming it exactly keeps
    # these two handlers, called hundreds of times a step, as cheap as a call can be.
    def _on_collision_started(self, sim: Any, obj_a: Any, obj_b: Any) -> None:
        self._collided[1] += (obj_a, obj_b)

    def _on_collision_ended(self, sim: Any, obj_a: Any, obj_b: Any) -> None:
        self._collided[0] += (obj_a, obj_b)

    def mark(self, step: int) -> None:
        """Stamp the collision events since the last mark with ``step`` (the frame showing them)."""
        ended, started = len(self._collided[0]), len(self._collided[1])
        last = self._collision_marks[-1] if self._collision_marks else (0, 0, 0)
        if (ended, started) != last[1:]:
            self._collision_marks.append((step, ended, started))

    def _resolve_collisions(self) -> None:
        """Turn the pending collision events (objects) into (steps, ids, started) lists."""
        if not self._collision_marks:
            return
        steps: list[int] = []
        ids: list[int] = []
        started: list[int] = []
        begin = [0, 0]
        for step, *ends in self._collision_marks:
            for kind in (0, 1):  # ended before started, as the collision system emits them
                objs = self._collided[kind][begin[kind] : ends[kind]]
                ids += [-1 if o is None else o.object_id for o in objs]
                count = len(objs) // 2
                steps += [step] * count
                started += [kind] * count
                begin[kind] = ends[kind]
        self._collided = [self._collided[0][begin[0] :], self._collided[1][begin[1] :]]
        self._collision_marks = []
        self._collision_rows.append((steps, ids, started))

    # ----- records ------------------------------------------------------------------------

    def drain(self) -> list[Record]:
        """The EVENTS and COLLISIONS records of everything logged since the last drain."""
        self.mark(self._sim.step_count)
        records: list[Record] = []
        if self._events:
            records.append((RecordKind.EVENTS, [json_bytes({"events": self._events})]))
            self._events = []
        self._resolve_collisions()
        if self._collision_rows:
            records.append((RecordKind.COLLISIONS, self._collision_parts()))
        return records

    def _collision_parts(self) -> list[Any]:
        """A COLLISIONS payload: pairs that started or ended, with the step of each."""
        steps = [v for rows in self._collision_rows for v in rows[0]]
        ids = [v for rows in self._collision_rows for v in rows[1]]
        started = [v for rows in self._collision_rows for v in rows[2]]
        self._collision_rows = []
        pairs = np.asarray(ids, dtype=np.int32).reshape(-1, 2)
        return [
            struct.pack("<I", len(steps)),
            np.asarray(steps, dtype=np.int32).tobytes(),
            np.ascontiguousarray(pairs[:, 0]).tobytes(),
            np.ascontiguousarray(pairs[:, 1]).tobytes(),
            np.asarray(started, dtype=np.uint8).tobytes(),
        ]
