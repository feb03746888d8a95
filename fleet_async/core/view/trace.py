"""Run recording ("trace"): every body's pose per frame and the run's events, in one file.

``sim.start_trace("run.fatrace")`` hooks a :class:`TraceWriter` into the step loop through
events (``post_step``, spawn / removal, action and collision events); it adds no branch to
``step_once``. The browser viewer (``fleet-async view run.fatrace``) replays the file, and
``fleet_async.viewer.TraceReader`` reads it back into numpy arrays.

The format (version :data:`FORMAT_VERSION`, specified in ``docs/trace-format.md``) is a
16-byte header followed by length-prefixed records. Poses are stored per frame as structure of
arrays over the frame's bodies: float32 positions, an int16 yaw and a flag byte, 15 bytes per
body per frame. Frames are buffered in numpy arrays and written a chunk at a time; nothing loops
over robots in Python per step.

Yaw, not a quaternion: the viewer is top-down, and the heading is what it draws. A robot that
tilts (an arm's link, a carried box) is drawn by its heading alone; the trace is not a
checkpoint and does not restore 3D orientation.
"""

from __future__ import annotations

import json
import logging
import math
import os
import queue
import struct
import threading
import time
from collections.abc import Callable
from enum import IntEnum
from pathlib import Path
from typing import TYPE_CHECKING, Any, BinaryIO

import numpy as np
import pybullet as p

from fleet_async.core.base.events import SimEvents
from fleet_async.core.world.state import COLLISION_CODES

if TYPE_CHECKING:
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = [
    "BYTES_PER_BODY_FRAME",
    "FLAG_CARRYING",
    "FLAG_FAILED",
    "FLAG_MOVING",
    "FORMAT_VERSION",
    "HEADER",
    "MAGIC",
    "RECORD",
    "YAW_SCALE",
    "RecordKind",
    "TraceApi",
    "TraceWriter",
]

logger = logging.getLogger(__name__)

MAGIC = b"FLEETTRC"
"""First 8 bytes of every trace file."""
FORMAT_VERSION = 1
"""Version of the file format this module writes (and the only one the readers accept)."""
HEADER = struct.Struct("<8sHHI")
"""File header: magic, format version, header size in bytes (16), reserved (0)."""
RECORD = struct.Struct("<II")
"""Record header: kind, payload length in bytes (the payload is then padded to 4 bytes)."""
FRAMES_HEADER = struct.Struct("<II")
"""FRAMES payload header: number of frames K, number of bodies N per frame."""
YAW_SCALE = math.pi / 32767.0
"""Radians per unit of the stored int16 yaw (resolution about 0.0055 degrees)."""
BYTES_PER_BODY_FRAME = 15
"""Pose bytes per body per frame: 3 x float32 position, int16 yaw, uint8 flags."""

FLAG_MOVING = 1
"""Flag bit: the body has a non-zero linear or angular velocity."""
FLAG_CARRYING = 2
"""Flag bit: something is attached to the body."""
FLAG_FAILED = 4
"""Flag bit: the body's last action failed (cleared when its next action starts)."""

_CHUNK_BYTES = 4 << 20  # frame bytes buffered before a FRAMES record is written
_MAX_CHUNK_FRAMES = 256
_STATIC_CODE = COLLISION_CODES["static"]


class RecordKind(IntEnum):
    """Kinds of record in a trace file (readers skip kinds they do not know)."""

    META = 1
    BODIES = 2
    LAYOUT = 3
    FRAMES = 4
    EVENTS = 5
    COLLISIONS = 6
    END = 7


def _pad(n: int) -> int:
    return (-n) % 4


class _FrameBuffer:
    """Up to K frames of N bodies as numpy arrays, written as one FRAMES record.

    The step loop fills it (:meth:`capture`); the writer thread writes it (:meth:`payload`)
    while the step loop fills the other buffer of the layout's pool.
    """

    def __init__(self, ids: np.ndarray, rows: np.ndarray, pool: queue.Queue[_FrameBuffer]) -> None:
        n = len(ids)
        self.ids = ids
        self.pool = pool
        # Contiguous rows (the usual case) are read by slicing, which is cheaper than gathering.
        contiguous = n > 0 and int(rows[-1]) - int(rows[0]) == n - 1
        self.sel: slice | np.ndarray = (
            slice(int(rows[0]), int(rows[-1]) + 1) if contiguous else rows
        )
        self.capacity = max(1, min(_MAX_CHUNK_FRAMES, _CHUNK_BYTES // max(1, 15 * n)))
        self.steps = np.zeros(self.capacity, dtype=np.int32)
        self.pos = np.zeros((self.capacity, n, 3), dtype=np.float32)
        self.yaw = np.zeros((self.capacity, n), dtype=np.int16)
        self.flags = np.zeros((self.capacity, n), dtype=np.uint8)
        self.count = 0
        self._scratch = np.empty((2, n))
        # object id -> index in the frame (-1: not in it), for setting flag bits in bulk
        self.lookup = np.full(int(ids.max()) + 1 if n else 0, -1, dtype=np.int64)
        self.lookup[ids] = np.arange(n)

    def indices_of(self, object_ids: Any) -> np.ndarray:
        """Frame indices of the given object ids that are in this frame's layout."""
        ids = np.fromiter(object_ids, dtype=np.int64)
        ids = ids[(ids >= 0) & (ids < len(self.lookup))]
        where = self.lookup[ids]
        return where[where >= 0]

    def capture(
        self,
        step: int,
        store: Any,
        extra_flags: np.ndarray | None,
        previous: tuple[np.ndarray, np.ndarray] | None,
    ) -> None:
        """Copy one frame out of the state store (the simulation's thread).

        Only what the frame needs crosses the memory bus: float32 positions and the int16
        yaw (a step at fleet scale has just evicted the store from the caches, so this is
        bound by memory traffic more than by arithmetic). FLAG_MOVING compares with the frame
        before, which is still in the cache: this buffer's previous frame, or ``previous``
        (positions, yaws) for the first frame of a chunk.
        """
        k, sel = self.count, self.sel
        self.steps[k] = step
        pos = self.pos[k]
        pos[...] = store.position[sel]
        quat = store.orientation[sel]
        a, b = self._scratch
        x, y, z, w = quat[:, 0], quat[:, 1], quat[:, 2], quat[:, 3]
        # yaw = atan2(2 (w z + x y), 1 - 2 (y^2 + z^2)), in preallocated arrays
        np.multiply(w, z, out=a)
        a += x * y
        a *= 2.0
        np.multiply(y, y, out=b)
        b += z * z
        b *= -2.0
        b += 1.0
        np.arctan2(a, b, out=a)
        a *= 1.0 / YAW_SCALE
        np.rint(a, out=a)
        yaw = self.yaw[k]
        yaw[...] = a
        flags = self.flags[k]
        before = (self.pos[k - 1], self.yaw[k - 1]) if k else previous
        if before is None:
            flags[...] = 0
        else:
            moved = flags.view(bool)
            np.not_equal(yaw, before[1], out=moved)  # FLAG_MOVING is bit 0
            moved |= (pos != before[0]).any(axis=1)
        if extra_flags is not None:
            flags |= extra_flags
        self.count += 1

    def payload(self) -> list[Any]:
        """The FRAMES payload as buffers to write in order (the writer thread)."""
        k, n = self.count, len(self.ids)
        return [
            FRAMES_HEADER.pack(k, n),
            self.steps[:k].view(np.uint8).data,
            self.pos[:k].reshape(-1).view(np.uint8).data,
            self.yaw[:k].reshape(-1).view(np.uint8).data,
            bytes(_pad(2 * k * n)),
            self.flags[:k].reshape(-1).data,
        ]

    def last_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the last frame's positions and yaws."""
        return self.pos[self.count - 1].copy(), self.yaw[self.count - 1].copy()

    def release(self) -> None:
        """Written: empty, back to the pool of its layout."""
        self.count = 0
        self.pool.put(self)


class _RecordThread:
    """Writes records to the file on a background thread, in the order they were queued.

    The simulation's thread hands over immutable bytes, or a frame buffer it no longer
    touches (it fills the other buffer of the pool meanwhile). A write error is raised on the
    simulation's thread at the next record or at :meth:`close`.
    """

    def __init__(self, file: BinaryIO) -> None:
        self._file = file
        self._queue: queue.Queue[tuple[int, list[Any] | None, _FrameBuffer | None] | None] = (
            queue.Queue()
        )
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="fleet-async-trace", daemon=True)
        self._thread.start()

    def put(
        self, kind: int, parts: list[Any] | None = None, frames: _FrameBuffer | None = None
    ) -> None:
        self._raise_error()
        self._queue.put((kind, parts, frames))

    def sync(self) -> None:
        """Wait until everything queued is written and flushed."""
        self._queue.join()
        self._raise_error()

    def close(self) -> None:
        """Write everything queued, stop the thread and close the file."""
        self._queue.put(None)
        self._thread.join()
        self._file.close()
        self._raise_error()

    def _raise_error(self) -> None:
        if self._error is not None:
            error, self._error = self._error, None
            raise error

    def _run(self) -> None:
        while True:
            item = self._queue.get()
            if item is None:
                self._queue.task_done()
                return
            kind, parts, frames = item
            try:
                if self._error is None:
                    if frames is not None:
                        parts = frames.payload()
                    self._write(kind, parts or [])
                    if self._queue.empty():
                        self._file.flush()  # a live viewer reads the file as it grows
            except BaseException as exc:  # reported on the simulation's thread
                self._error = exc
            finally:
                if frames is not None:
                    frames.release()
                self._queue.task_done()

    def _write(self, kind: int, parts: list[Any]) -> None:
        size = sum(memoryview(part).nbytes for part in parts)
        self._file.write(RECORD.pack(kind, size))
        for part in parts:
            self._file.write(part)
        pad = _pad(size)
        if pad:
            self._file.write(bytes(pad))


class TraceWriter:
    """Records a simulation to a trace file while it runs.

    Args:
        sim: The simulation.
        path: Output file (``.fatrace`` by convention); parent directories are created.
        every_n_steps: Record a frame every this many steps (1: every step).
        flush_seconds: Wall seconds after which buffered frames are written even if the chunk
            is not full, so a live viewer following the file sees them.
        clock: Wall clock in seconds (injectable for tests).

    Raises:
        ValueError: if ``every_n_steps`` is not a whole number >= 1 or ``flush_seconds`` <= 0.
    """

    def __init__(
        self,
        sim: MultiRobotSimulationCore,
        path: str | os.PathLike[str],
        every_n_steps: int = 1,
        *,
        flush_seconds: float = 1.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if (
            isinstance(every_n_steps, bool)
            or not isinstance(every_n_steps, int)
            or every_n_steps < 1
        ):
            raise ValueError(
                f"trace every_n_steps: expected a whole number >= 1, got {every_n_steps!r}"
            )
        if not (isinstance(flush_seconds, (int, float)) and flush_seconds > 0):
            raise ValueError(f"trace flush_seconds: expected a number > 0, got {flush_seconds!r}")
        self._sim = sim
        self._path = Path(path)
        self._every = every_n_steps
        self._flush_seconds = float(flush_seconds)
        self._clock = clock
        self._records: _RecordThread | None = None
        self._frames: _FrameBuffer | None = None
        self._frame_pool: queue.Queue[_FrameBuffer] | None = None
        self._previous: tuple[np.ndarray, np.ndarray] | None = None  # last frame handed over
        self._layout_dirty = True
        self._new_bodies: list[Any] = []
        self._static_ids: set[int] = set()
        self._shapes: dict[str, int] = {}
        self._footprints: dict[tuple[Any, ...], dict[str, Any]] = {}
        self._events: list[list[Any]] = []
        # Collision events arrive by the hundred per step at fleet scale, so their handlers
        # only append the two objects; ids and steps are resolved in bulk when flushing.
        self._collided: list[list[Any]] = [[], []]  # [ended objects, started objects] (pairs)
        self._collision_marks: list[tuple[int, int, int]] = []  # (step, ended len, started len)
        self._collision_rows: list[tuple[list[int], list[int], list[int]]] = []  # resolved
        self._failed: set[int] = set()
        self._flag_version = 0  # bumped whenever the failed or colliding sets change
        self._flag_key: tuple[Any, ...] | None = None
        self._flag_mask: np.ndarray | None = None
        self._last_step = -1
        self._frame_count = 0
        self._last_flush = 0.0
        self._handlers: list[tuple[str, Callable[..., Any]]] = [
            (SimEvents.OBJECT_SPAWNED, self._on_spawned),
            (SimEvents.OBJECT_REMOVED, self._on_removed),
            (SimEvents.ACTION_STARTED, self._on_action_started),
            (SimEvents.ACTION_COMPLETED, self._on_action_ended),
            (SimEvents.ACTION_FAILED, self._on_action_ended),
            (SimEvents.COLLISION_STARTED, self._on_collision_started),
            (SimEvents.COLLISION_ENDED, self._on_collision_ended),
        ]

    @property
    def path(self) -> str:
        """The output file."""
        return str(self._path)

    @property
    def is_tracing(self) -> bool:
        """Whether the writer is between :meth:`start` and :meth:`stop`."""
        return self._records is not None

    @property
    def frame_count(self) -> int:
        """Frames recorded so far."""
        return self._frame_count

    @property
    def every_n_steps(self) -> int:
        """Steps between two frames."""
        return self._every

    # ----- start / stop -----------------------------------------------------------------

    def start(self) -> None:
        """Open the file, write the header and metadata, record the first frame, hook in.

        Raises:
            RuntimeError: if this writer was started before.
            OSError: if the file cannot be created.
        """
        if self._records is not None or self._last_step >= 0:
            raise RuntimeError(f"TraceWriter({self.path!r}) was already started")
        self._path.parent.mkdir(parents=True, exist_ok=True)
        file = open(self._path, "wb")  # noqa: SIM115  # closed by the record thread
        file.write(HEADER.pack(MAGIC, FORMAT_VERSION, HEADER.size, 0))
        self._records = _RecordThread(file)
        sim = self._sim
        self._write_json(
            RecordKind.META,
            {
                "format": "fleet_async trace",
                "version": FORMAT_VERSION,
                "timestep": sim.params.timestep,
                "every_n_steps": self._every,
                "start_step": sim.step_count,
                "yaw_scale": YAW_SCALE,
                "flags": {
                    "moving": FLAG_MOVING,
                    "carrying": FLAG_CARRYING,
                    "failed": FLAG_FAILED,
                },
                "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            },
        )
        self._new_bodies = list(sim.sim_objects)
        # Pairs already touching start, for the trace, in its first frame.
        for a, b in sim.get_active_collision_pairs():
            self._collided[1] += (sim.get_object_by_id(a), sim.get_object_by_id(b))
        for event, handler in self._handlers:
            sim.events.on(event, handler)
        # Low priority: a frame shows what the other post-step handlers did this step.
        sim.events.on(SimEvents.POST_STEP, self._on_post_step, priority=-200)
        self._last_flush = self._clock()
        self._capture(sim.step_count)
        logger.info("tracing to %s (a frame every %d step(s))", self.path, self._every)

    def stop(self) -> str | None:
        """Record the final frame if it is not in yet, write the end record and close the file.

        Returns:
            The file's path, or None if the writer was not tracing.
        """
        if self._records is None:
            return None
        sim = self._sim
        sim.events.off(SimEvents.POST_STEP, self._on_post_step)
        for event, handler in self._handlers:
            sim.events.off(event, handler)
        if sim.step_count != self._last_step:
            self._capture(sim.step_count)
        self._flush()
        self._write_json(
            RecordKind.END,
            {
                "last_step": self._last_step,
                "frames": self._frame_count,
                "sim_time": self._last_step * sim.params.timestep,
            },
        )
        records, self._records = self._records, None
        records.close()
        logger.info("saved trace %s (%d frames)", self.path, self._frame_count)
        return self.path

    def flush(self) -> None:
        """Write every frame and event recorded so far to the file now (and wait for it)."""
        if self._records is not None:
            self._flush()
            self._records.sync()

    # ----- events -----------------------------------------------------------------------

    def event(self, kind: str, object_id: int | None = None, **data: Any) -> None:
        """Add an event to the trace's log (``sim.trace_event`` lands here).

        Args:
            kind: What happened, e.g. ``"mission_error"``.
            object_id: The object it concerns, if any (the viewer lists it under that object).
            **data: JSON-serialisable details (anything else is stored as its ``str``).
        """
        self._events.append([self._now(), self._step_stamp(), str(kind), object_id, data])

    def _step_stamp(self) -> int:
        # Inside step_once the event shows in the frame at the end of the step.
        return self._sim.step_count + (1 if self._sim.in_step else 0)

    def _now(self) -> float:
        return self._step_stamp() * self._sim.params.timestep

    def _on_spawned(self, obj: Any, **_: Any) -> None:
        self._new_bodies.append(obj)
        self._layout_dirty = True

    def _on_removed(self, obj: Any, **_: Any) -> None:
        # Pending collision events hold objects; resolve their ids while this one has its id.
        self._mark_collisions(self._step_stamp())
        self._resolve_collisions()
        self._layout_dirty = True
        if obj.object_id in self._failed:
            self._failed.discard(obj.object_id)
            self._flag_version += 1
        self.event("removed", obj.object_id)

    def _on_action_started(self, agent: Any, action: Any, **_: Any) -> None:
        if agent.object_id in self._failed:
            self._failed.discard(agent.object_id)
            self._flag_version += 1
        t = action.start_time if action.start_time is not None else self._now()
        self._events.append(
            [
                t,
                self._step_stamp(),
                "action_started",
                agent.object_id,
                {"action": type(action).__name__},
            ]
        )

    def _on_action_ended(self, agent: Any, action: Any, **_: Any) -> None:
        status = getattr(action.status, "value", str(action.status))
        if status == "failed":
            self._failed.add(agent.object_id)
            self._flag_version += 1
        t = action.end_time if action.end_time is not None else self._now()
        data: dict[str, Any] = {"action": type(action).__name__, "status": status}
        if action.error_message:
            data["reason"] = action.error_message
        self._events.append([t, self._step_stamp(), "action_ended", agent.object_id, data])

    # The simulation bus's collision payload is (sim, obj_a, obj_b); naming it exactly keeps
    # these two handlers, called hundreds of times a step, as cheap as a call can be.
    def _on_collision_started(self, sim: Any, obj_a: Any, obj_b: Any) -> None:
        self._collided[1] += (obj_a, obj_b)

    def _on_collision_ended(self, sim: Any, obj_a: Any, obj_b: Any) -> None:
        self._collided[0] += (obj_a, obj_b)

    def _mark_collisions(self, step: int) -> None:
        """Stamp the collision events since the last mark with ``step`` (the frame showing them)."""
        ended, started = len(self._collided[0]), len(self._collided[1])
        last = self._collision_marks[-1] if self._collision_marks else (0, 0, 0)
        if (ended, started) != last[1:]:
            self._collision_marks.append((step, ended, started))

    # ----- frames -----------------------------------------------------------------------

    def _on_post_step(self, step: int, **_: Any) -> None:
        self._mark_collisions(step)
        if step % self._every == 0:
            self._capture(step)

    def _capture(self, step: int) -> None:
        if self._layout_dirty:
            self._flush()
            self._describe_new_bodies()
            self._rebuild_layout()
        frames = self._frames
        assert frames is not None  # set by _rebuild_layout
        frames.capture(step, self._sim.state, self._extra_flags(frames), self._previous)
        self._last_step = step
        self._frame_count += 1
        if (
            frames.count == frames.capacity
            or self._clock() - self._last_flush >= self._flush_seconds
        ):
            self._flush()

    def _extra_flags(self, frames: _FrameBuffer) -> np.ndarray | None:
        """Carrying / failed / colliding bits per body of the layout; cached while unchanged."""
        attachments = self._sim.attachments
        parents = attachments.parent_ids() if len(attachments) else set()
        key = (id(frames), self._flag_version, parents)
        if key == self._flag_key:
            return self._flag_mask
        self._flag_key = key
        if not (parents or self._failed):
            self._flag_mask = None
            return None
        mask = np.zeros(len(frames.ids), dtype=np.uint8)
        for ids, bit in (
            (parents, FLAG_CARRYING),
            (self._failed, FLAG_FAILED),
        ):
            if ids:
                mask[frames.indices_of(ids)] |= bit
        self._flag_mask = mask
        return mask

    def _describe_new_bodies(self) -> None:
        sim, bodies, shapes = self._sim, [], []
        for obj in self._new_bodies:
            if obj.sim_core is not sim:  # spawned and removed again between two frames
                continue
            shape, static_pose = describe_body(obj, sim.client, self._footprints)
            key = json.dumps(shape, sort_keys=True)
            if key not in self._shapes:
                self._shapes[key] = len(self._shapes)
                shapes.append(shape)
            entry: dict[str, Any] = {
                "id": obj.object_id,
                "name": obj.name,
                "kind": "agent" if obj.is_agent else ("static" if obj.is_static else "object"),
                "class": type(obj).__name__,
                "shape": self._shapes[key],
            }
            if obj.is_static:
                entry["pose"] = static_pose
                self._static_ids.add(obj.object_id)
            if obj.pickable and not obj.is_agent:
                entry["pickable"] = True
            bodies.append(entry)
        self._new_bodies = []
        if bodies:
            self._write_json(
                RecordKind.BODIES,
                {"shape_base": len(self._shapes) - len(shapes), "shapes": shapes, "bodies": bodies},
            )

    def _rebuild_layout(self) -> None:
        """The bodies each frame holds: every live, non-static object, in state-row order."""
        store = self._sim.state
        rows = store.live_rows()
        rows = rows[store.collision_mode[rows] != _STATIC_CODE]
        ids = store.object_id[rows]
        if self._static_ids:
            keep = ~np.isin(ids, np.fromiter(self._static_ids, dtype=np.int64))
            rows, ids = rows[keep], ids[keep]
        # Two buffers per layout: one fills while the record thread writes the other.
        pool: queue.Queue[_FrameBuffer] = queue.Queue()
        pool.put(_FrameBuffer(ids.astype(np.int32), rows, pool))
        self._frames = _FrameBuffer(ids.astype(np.int32), rows, pool)
        self._frame_pool = pool
        self._previous = None
        self._flag_key = None
        payload = struct.pack("<I", len(ids)) + ids.astype("<i4").tobytes()
        self._write(RecordKind.LAYOUT, payload)
        self._layout_dirty = False

    def _flush(self) -> None:
        """Hand buffered events, collisions and frames (in that order) to the record thread."""
        self._mark_collisions(self._sim.step_count)
        if self._events:
            self._write_json(RecordKind.EVENTS, {"events": self._events})
            self._events = []
        self._resolve_collisions()
        if self._collision_rows:
            self._write_collisions()
        frames = self._frames
        if frames is not None and frames.count:
            assert self._records is not None
            assert self._frame_pool is not None
            self._previous = frames.last_frame()
            self._records.put(RecordKind.FRAMES, frames=frames)
            self._frames = self._frame_pool.get()  # waits only if the disk falls behind
        self._last_flush = self._clock()

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

    def _write_collisions(self) -> None:
        """One COLLISIONS record: pairs that started or ended, with the step of each."""
        steps = [v for rows in self._collision_rows for v in rows[0]]
        ids = [v for rows in self._collision_rows for v in rows[1]]
        started = [v for rows in self._collision_rows for v in rows[2]]
        self._collision_rows = []
        pairs = np.asarray(ids, dtype=np.int32).reshape(-1, 2)
        self._write_parts(
            RecordKind.COLLISIONS,
            [
                struct.pack("<I", len(steps)),
                np.asarray(steps, dtype=np.int32).tobytes(),
                np.ascontiguousarray(pairs[:, 0]).tobytes(),
                np.ascontiguousarray(pairs[:, 1]).tobytes(),
                np.asarray(started, dtype=np.uint8).tobytes(),
            ],
        )

    def _write(self, kind: RecordKind, payload: bytes) -> None:
        self._write_parts(kind, [payload])

    def _write_parts(self, kind: RecordKind, parts: list[Any]) -> None:
        assert self._records is not None
        self._records.put(int(kind), parts)

    def _write_json(self, kind: RecordKind, value: Any) -> None:
        text = json.dumps(value, separators=(",", ":"), default=str, allow_nan=False)
        self._write(kind, text.encode("utf-8"))


# ----- body footprints ------------------------------------------------------------------

_GEOM_SPHERE, _GEOM_BOX, _GEOM_CYLINDER, _GEOM_MESH, _GEOM_CAPSULE = 2, 3, 4, 5, 7
_MARKER = {
    "type": "circle",
    "center": [0.0, 0.0],
    "radius": 0.05,
    "z": [-0.05, 0.05],
    "rgba": [0.5, 0.5, 0.5, 1.0],
}


def _yaw(q: Any) -> float:
    x, y, z, w = (float(v) for v in q)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _half_extents(body: int, link: int, geom: int, dims: Any, client: int) -> np.ndarray | None:
    """Half extents of one visual primitive in its own frame (None: not drawn from above)."""
    if geom == _GEOM_BOX:
        return np.asarray(dims[:3], dtype=float) / 2.0
    if geom == _GEOM_SPHERE:
        return np.full(3, float(dims[0]))
    if geom in (_GEOM_CYLINDER, _GEOM_CAPSULE):
        length, radius = float(dims[0]), float(dims[1])
        return np.array([radius, radius, length / 2.0 + (radius if geom == _GEOM_CAPSULE else 0)])
    if geom == _GEOM_MESH:  # the mesh's extent is not in the visual data: use the link's AABB
        lo, hi = p.getAABB(body, link, physicsClientId=client)
        return (np.asarray(hi) - np.asarray(lo)) / 2.0
    return None  # planes and heightfields


def _part_frame(
    body: int, link: int, local_pos: Any, local_orn: Any, client: int, base_inv: Any
) -> tuple[Any, Any]:
    """Pose of a visual primitive in the body (base inertial) frame."""
    if link < 0 or base_inv is None:
        return local_pos, local_orn
    state = p.getLinkState(body, link, computeForwardKinematics=1, physicsClientId=client)
    rel_pos, rel_orn = p.multiplyTransforms(base_inv[0], base_inv[1], state[0], state[1])
    return p.multiplyTransforms(rel_pos, rel_orn, local_pos, local_orn)


def describe_body(
    obj: Any, client: int, cache: dict[tuple[Any, ...], dict[str, Any]]
) -> tuple[dict[str, Any], list[float]]:
    """Top-down footprint of ``obj`` in its body frame, and its pose ``[x, y, z, yaw]``.

    The footprint is the body-frame bounding box of every visual primitive of every link (a
    circle for a lone sphere or upright cylinder), coloured like the primitive that covers
    the most floor; ``z`` is the body-frame height range, for the viewer's height filter.
    ``cache`` holds the footprints of single-link bodies by their visual data, so a fleet of
    identical robots is measured once.
    """
    pose = obj.get_pose()
    where = [*(float(v) for v in pose.position), _yaw(pose.orientation)]
    body = obj.body_id
    if body < 0:
        return dict(_MARKER), where
    visuals = p.getVisualShapeData(body, physicsClientId=client)
    # Links and meshes depend on the body's own joint state and AABB: computed every time.
    key = (
        tuple(v[1:] for v in visuals)
        if all(v[1] < 0 and v[2] != _GEOM_MESH for v in visuals)
        else None
    )
    if key is not None and key in cache:
        return dict(cache[key]), where
    shape = _footprint(body, visuals, client)
    if key is not None:
        cache[key] = shape
    return dict(shape), where


def _footprint(body: int, visuals: Any, client: int) -> dict[str, Any]:
    base_inv = None
    if any(v[1] >= 0 for v in visuals):
        base = p.getBasePositionAndOrientation(body, physicsClientId=client)
        base_inv = p.invertTransform(base[0], base[1])
    lows, highs, colours, areas, round_part = [], [], [], [], False
    for v in visuals:
        link, geom, dims, local_pos, local_orn, rgba = v[1], v[2], v[3], v[5], v[6], v[7]
        half = _half_extents(body, link, geom, dims, client)
        if half is None:
            continue
        pos, orn = _part_frame(body, link, local_pos, local_orn, client, base_inv)
        rot = np.asarray(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
        reach = np.abs(rot) @ half  # half extents of the rotated primitive's bounding box
        lows.append(np.asarray(pos) - reach)
        highs.append(np.asarray(pos) + reach)
        colours.append([round(float(c), 4) for c in rgba])
        areas.append(float(reach[0] * reach[1]))
        round_part = geom == _GEOM_SPHERE or (
            geom in (_GEOM_CYLINDER, _GEOM_CAPSULE) and abs(rot[2, 2]) > 0.999
        )
    if not lows:
        return dict(_MARKER)
    lo, hi = np.min(lows, axis=0), np.max(highs, axis=0)
    center = [round(float(c), 5) for c in (lo[:2] + hi[:2]) / 2.0]
    shape: dict[str, Any] = {
        "type": "circle" if (round_part and len(lows) == 1) else "box",
        "center": center,
        "z": [round(float(lo[2]), 5), round(float(hi[2]), 5)],
        "rgba": colours[int(np.argmax(areas))],
    }
    if shape["type"] == "circle":
        shape["radius"] = round(float(hi[0] - lo[0]) / 2.0, 5)
    else:
        shape["half"] = [round(float(h), 5) for h in (hi[:2] - lo[:2]) / 2.0]
    return shape


class TraceApi:
    """``start_trace`` / ``stop_trace`` / ``trace_event`` for MultiRobotSimulationCore."""

    _tracer: TraceWriter | None = None

    @property
    def tracer(self) -> TraceWriter | None:
        """The running trace writer, or None."""
        tracer = self._tracer
        return tracer if tracer is not None and tracer.is_tracing else None

    def start_trace(
        self,
        path: str | os.PathLike[str] = "run.fatrace",
        every_n_steps: int | None = None,
        *,
        fps: float | None = None,
        flush_seconds: float = 1.0,
    ) -> TraceWriter:
        """Start recording a trace of this run (poses per frame plus the event log).

        The first frame is the state now; later frames are taken after steps. The file is
        complete once :meth:`stop_trace` (or ``close``) has written its end record.

        Args:
            path: Output file; parent directories are created.
            every_n_steps: Record a frame every this many steps (default 1).
            fps: Instead of ``every_n_steps``: frames per sim second (rounded to whole steps).
            flush_seconds: Wall seconds between writes of buffered frames (for live viewing).

        Returns:
            The running writer.

        Raises:
            RuntimeError: if a trace is already running.
            ValueError: for bad arguments, or both ``every_n_steps`` and ``fps``.
        """
        running = self.tracer
        if running is not None:
            raise RuntimeError(
                f"start_trace: a trace to {running.path!r} is already running; call stop_trace()"
            )
        if every_n_steps is not None and fps is not None:
            raise ValueError("start_trace: give every_n_steps or fps, not both")
        sim: MultiRobotSimulationCore = self  # type: ignore[assignment]  # mixed into the sim
        if fps is not None:
            if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not fps > 0:
                raise ValueError(f"start_trace fps: expected a number > 0, got {fps!r}")
            every_n_steps = max(1, round(1.0 / (fps * sim.params.timestep)))
        writer = TraceWriter(
            sim, path, 1 if every_n_steps is None else every_n_steps, flush_seconds=flush_seconds
        )
        writer.start()
        self._tracer = writer
        return writer

    def stop_trace(self) -> str | None:
        """Finish the running trace (final frame, end record) and close its file.

        Returns:
            The file's path, or None if no trace was running.
        """
        tracer, self._tracer = self._tracer, None
        return tracer.stop() if tracer is not None else None

    def trace_event(self, kind: str, object_id: int | None = None, **data: Any) -> None:
        """Log an event in the running trace (a no-op when no trace runs).

        The mission layer and user code call it for what the simulator cannot see, e.g.
        ``sim.trace_event("mission_error", object_id=robot.object_id, message=str(exc))``.
        The viewer lists the event under ``object_id`` and in the run's event log.
        """
        tracer = self._tracer
        if tracer is not None and tracer.is_tracing:
            tracer.event(kind, object_id, **data)
