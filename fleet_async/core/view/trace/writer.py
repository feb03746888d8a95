"""The trace writer: every body's pose per frame and the run's events, in one file.

:class:`TraceWriter` watches the simulation without being part of its step: a step observer
(``sim.add_step_observer``) takes the frames, events tell it of spawns, removals, skipped
steps, actions and mission errors, and a collision listener of contacts. A step observer,
unlike a POST_STEP handler, leaves the drivers free to skip empty steps (``sim/idle.py``): a
skipped span is recorded by its first and last frame slots (nothing moved in between, so the
viewer holds the pose), not by a frame per step.

The pieces: the format (``format.py``, specified in ``docs/trace-format.md``), frame buffers
(``frames.py``), the record thread that writes the file (``file.py``), the event log
(``events.py``) and body footprints (``footprints.py``); this module ties them to the
simulation.
"""

from __future__ import annotations

import json
import logging
import os
import queue
import struct
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fleet_async.core.base.events import SimEvents
from fleet_async.core.view.trace.events import TraceEventLog, json_bytes
from fleet_async.core.view.trace.file import RecordThread
from fleet_async.core.view.trace.footprints import describe_body
from fleet_async.core.view.trace.format import (
    FLAG_CARRYING,
    FLAG_FAILED,
    FLAG_MOVING,
    FORMAT_VERSION,
    HEADER,
    MAGIC,
    YAW_SCALE,
    RecordKind,
)
from fleet_async.core.view.trace.frames import FrameBuffer, HeadingTracker
from fleet_async.core.world.state import COLLISION_CODES

if TYPE_CHECKING:
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["TraceWriter"]

logger = logging.getLogger(__name__)

_STATIC_CODE = COLLISION_CODES["static"]


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
        sim: SimulationKernel,
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
        self._records: RecordThread | None = None
        self._frames: FrameBuffer | None = None
        self._frame_pool: queue.Queue[FrameBuffer] | None = None
        self._previous: tuple[np.ndarray, np.ndarray] | None = None  # last frame handed over
        self._layout_dirty = True
        self._new_bodies: list[Any] = []
        self._static_ids: set[int] = set()
        self._shapes: dict[str, int] = {}
        self._footprints: dict[tuple[Any, ...], dict[str, Any]] = {}
        self._log = TraceEventLog(sim)
        self._flag_key: tuple[Any, ...] | None = None
        self._flag_mask: np.ndarray | None = None
        self._last_step = -1
        self._frame_count = 0
        self._last_flush = 0.0
        # Each handler names the payload keys it reads and takes **_ for the rest.
        self._handlers: list[tuple[str, Callable[..., Any]]] = [
            (SimEvents.OBJECT_SPAWNED, self._on_spawned),
            (SimEvents.OBJECT_REMOVED, self._on_removed),
            (SimEvents.STEPS_SKIPPED, self._on_skipped),
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
        self._records = RecordThread(file)
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
        self._log.hook()
        scenery = getattr(sim, "trace_scenery", None)  # maps and the route graph (viewer)
        for kind, data in scenery() if scenery is not None else ():
            self._log.event(kind, None, **data)
        for event, handler in self._handlers:
            sim.events.on(event, handler)
        # Called after every POST_STEP handler, so a frame shows what they did this step.
        sim.add_step_observer(self._after_step)
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
        sim.remove_step_observer(self._after_step)
        for event, handler in self._handlers:
            sim.events.off(event, handler)
        self._log.unhook()
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
        self._log.event(kind, object_id, **data)

    def command(self, step: int, vehicle: str, command: Any) -> None:
        """Record a fleet master's command (JSON data) applied to ``vehicle`` at the step
        boundary where the step count was ``step``: a replay applies it there again."""
        self._log.command(step, vehicle, command)

    def _on_spawned(self, obj: Any, **_: Any) -> None:
        self._new_bodies.append(obj)
        self._layout_dirty = True

    def _on_removed(self, obj: Any, **_: Any) -> None:
        self._log.note_removed(obj)
        self._layout_dirty = True

    # ----- frames -----------------------------------------------------------------------

    def _after_step(self, step: int) -> None:
        if step % self._every == 0:
            self._capture(step)

    def _on_skipped(self, step: int, count: int, **_: Any) -> None:
        """Steps ``step .. step + count - 1`` were skipped (``sim.skip_steps``): nothing moved,
        so of the frame slots in the span only the first and the last are written. The viewer
        interpolates between frames, so these two hold the pose over the span as the frames of
        a run that stepped through it would; the ones between would repeat them."""
        every = self._every
        first = -(-(step + 1) // every) * every  # the first slot after one of the span's steps
        last = (step + count) // every * every
        if first <= last:
            self._capture(first)
            if last > first:
                self._capture(last)

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

    def _extra_flags(self, frames: FrameBuffer) -> np.ndarray | None:
        """Carrying / failed bits per body of the layout; cached while unchanged."""
        attachments = self._sim.attachments
        parents = attachments.parent_ids() if len(attachments) else set()
        failed = self._log.failed
        key = (id(frames), self._log.flag_version, parents)
        if key == self._flag_key:
            return self._flag_mask
        self._flag_key = key
        if not (parents or failed):
            self._flag_mask = None
            return None
        mask = np.zeros(len(frames.ids), dtype=np.uint8)
        for ids, bit in ((parents, FLAG_CARRYING), (failed, FLAG_FAILED)):
            if ids:
                mask[frames.indices_of(ids)] |= bit
        self._flag_mask = mask
        return mask

    def _describe_new_bodies(self) -> None:
        sim, bodies, shapes = self._sim, [], []
        for obj in self._new_bodies:
            if obj.sim_core is not sim:  # spawned and removed again between two frames
                continue
            shape, static_pose = describe_body(obj, sim.world, self._footprints)
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
            if obj.is_agent and not obj.is_robot:  # a door, lift or workcell: not a robot
                entry["device"] = True
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
        pool: queue.Queue[FrameBuffer] = queue.Queue()
        headings = HeadingTracker(len(ids))
        pool.put(FrameBuffer(ids.astype(np.int32), rows, pool, headings))
        self._frames = FrameBuffer(ids.astype(np.int32), rows, pool, headings)
        self._frame_pool = pool
        self._previous = None
        self._flag_key = None
        payload = struct.pack("<I", len(ids)) + ids.astype("<i4").tobytes()
        self._write(RecordKind.LAYOUT, [payload])
        self._layout_dirty = False

    def _flush(self) -> None:
        """Hand buffered events, collisions and frames (in that order) to the record thread."""
        for kind, parts in self._log.drain():
            self._write(kind, parts)
        frames = self._frames
        if frames is not None and frames.count:
            assert self._records is not None
            assert self._frame_pool is not None
            self._previous = frames.last_frame()
            self._records.put(RecordKind.FRAMES, frames=frames)
            self._frames = self._frame_pool.get()  # waits only if the disk falls behind
        self._last_flush = self._clock()

    def _write(self, kind: RecordKind, parts: list[Any]) -> None:
        assert self._records is not None
        self._records.put(int(kind), parts)

    def _write_json(self, kind: RecordKind, value: Any) -> None:
        self._write(kind, [json_bytes(value)])
