"""The trace's event log: actions, collisions, removals, mission errors and user events,
stamped with steps.

The log listens on the simulation's event bus (actions, mission errors) and to the collision
system (one call per check with its arrays of pairs that ended and started) while a trace
runs, keeps what it hears in Python lists and hands it to the writer as EVENTS and COLLISIONS
records when the writer flushes (before the FRAMES record that shows their step). It also
keeps the set of bodies whose last action failed, for the frames' FLAG_FAILED bit.
"""

from __future__ import annotations

import json
import struct
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from fleet_async.core.base.events import SimEvents
from fleet_async.core.view.trace.action_info import describe_end, describe_start
from fleet_async.core.view.trace.format import RecordKind

if sys.version_info < (3, 11):  # anyio depends on the backport there
    from exceptiongroup import BaseExceptionGroup

if TYPE_CHECKING:
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["TraceEventLog", "json_bytes"]

_NO_PAIRS = np.empty((0, 2), dtype=np.int64)

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

    def __init__(self, sim: SimulationKernel) -> None:
        self._sim = sim
        self._events: list[list[Any]] = []
        # Collisions arrive by the hundred per step at fleet scale: the collision system hands
        # over each check's (K, 2) arrays of pairs in one call; they are joined at flush time.
        self._collisions: list[tuple[int, np.ndarray, np.ndarray]] = []
        self._commands: list[list[Any]] = []
        self._failed: set[int] = set()
        self.flag_version = 0
        """Bumped whenever the set of failed bodies changes (the writer caches flag masks)."""
        self._errors_seen: list[BaseException] = []  # kept alive, so ids stay unique
        # Each handler names the payload keys it reads and takes **_ for the rest.
        self._handlers: list[tuple[str, Callable[..., Any]]] = [
            (SimEvents.ACTION_STARTED, self._on_action_started),
            (SimEvents.ACTION_COMPLETED, self._on_action_ended),
            (SimEvents.ACTION_FAILED, self._on_action_ended),
            (SimEvents.MISSION_FAILED, self._on_mission_failed),
            (SimEvents.TASK_COMPLETED, self._on_task_completed),
            (SimEvents.TASK_FAILED, self._on_task_failed),
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
            pairs = np.array(active, dtype=np.int64).reshape(-1, 2)
            self._collisions.append((sim.step_count, _NO_PAIRS, pairs))
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
        data = {"action": type(action).__name__, **describe_start(action, self._sim.sim_objects)}
        self._events.append([t, self.step_stamp(), "action_started", agent.object_id, data])

    def _on_action_ended(self, agent: Any, action: Any, **_: Any) -> None:
        status = getattr(action.status, "value", str(action.status))
        if status == "failed":
            self._failed.add(agent.object_id)
            self.flag_version += 1
        t = action.end_time if action.end_time is not None else self._now()
        data: dict[str, Any] = {"action": type(action).__name__, "status": status}
        data.update(describe_end(action))
        if action.error_message:
            data["reason"] = action.error_message
        self._events.append([t, self.step_stamp(), "action_ended", agent.object_id, data])

    def _on_mission_failed(self, mission: str, error: BaseException, **_: Any) -> None:
        # A parent that re-raises its children's errors in a group is told again: log each
        # exception once, under the mission it ended first.
        for leaf in _leaves(error):
            if any(leaf is seen for seen in self._errors_seen):
                continue
            self._errors_seen.append(leaf)
            holder = getattr(leaf, "agent", None) or getattr(leaf, "obj", None)
            data = {"mission": mission, "error": type(leaf).__name__, "message": str(leaf)}
            self.event("mission_error", getattr(holder, "object_id", None), **data)

    def _on_task_completed(self, agent: Any = None, task: Any = None, **_: Any) -> None:
        self._task_event("task_completed", agent, task)

    def _on_task_failed(self, agent: Any = None, task: Any = None, **_: Any) -> None:
        self._task_event("task_failed", agent, task)

    def _task_event(self, kind: str, agent: Any, task: Any) -> None:
        """A task (an order, a job) ended: ``task`` is its ``str``, what the timeline shows."""
        self.event(kind, getattr(agent, "object_id", None), task=str(task))

    def command(self, step: int, vehicle: str, command: Any) -> None:
        """A fleet master's command, applied to ``vehicle`` at the boundary before ``step``
        ran (``step`` = the step count then); ``command`` is its JSON data."""
        self._commands.append([int(step), str(vehicle), command])

    # ----- collisions -----------------------------------------------------------------------

    def _on_collisions(self, ended: np.ndarray, started: np.ndarray) -> None:
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
        if self._commands:
            records.append((RecordKind.COMMANDS, [json_bytes({"commands": self._commands})]))
            self._commands = []
        return records

    def _collision_parts(self) -> list[Any]:
        """A COLLISIONS payload: pairs that ended or started (in that order per check), with
        the step of the frame that shows each."""
        lists = [pairs for _, ended, started in self._collisions for pairs in (ended, started)]
        counts = np.fromiter(map(len, lists), dtype=np.int64, count=len(lists))
        total = int(counts.sum())
        stamps = np.fromiter((s for s, _, _ in self._collisions), dtype=np.int32)
        ids = np.concatenate(lists).astype(np.int32) if total else np.empty((0, 2), np.int32)
        return [
            struct.pack("<I", total),
            np.repeat(np.repeat(stamps, 2), counts).tobytes(),
            np.ascontiguousarray(ids[:, 0]).tobytes(),
            np.ascontiguousarray(ids[:, 1]).tobytes(),
            np.repeat(np.tile(np.array([0, 1], dtype=np.uint8), len(stamps)), counts).tobytes(),
        ]


def _leaves(error: BaseException) -> list[BaseException]:
    """The exceptions inside (nested) exception groups, or ``[error]``."""
    if isinstance(error, BaseExceptionGroup):
        return [leaf for inner in error.exceptions for leaf in _leaves(inner)]
    return [error]
