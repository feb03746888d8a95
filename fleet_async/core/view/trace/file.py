"""The trace's record thread: writes records to the file in the order they were queued.

File writes (and, for frames, building the payload views) happen off the simulation's thread,
so a slow disk costs the step loop nothing until both frame buffers of a layout are full.
"""

from __future__ import annotations

import queue
import threading
from typing import Any, BinaryIO

from fleet_async.core.view.trace.format import RECORD, padding
from fleet_async.core.view.trace.frames import FrameBuffer

__all__ = ["RecordThread"]


class RecordThread:
    """Writes records to the file on a background thread, in the order they were queued.

    The simulation's thread hands over immutable bytes, or a frame buffer it no longer
    touches (it fills the other buffer of the pool meanwhile). A write error is raised on the
    simulation's thread at the next record or at :meth:`close`.
    """

    def __init__(self, file: BinaryIO) -> None:
        self._file = file
        self._queue: queue.Queue[tuple[int, list[Any] | None, FrameBuffer | None] | None] = (
            queue.Queue()
        )
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="fleet-async-trace", daemon=True)
        self._thread.start()

    def put(
        self, kind: int, parts: list[Any] | None = None, frames: FrameBuffer | None = None
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
        pad = padding(size)
        if pad:
            self._file.write(bytes(pad))
