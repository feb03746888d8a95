"""Reading a trace file back: header, records, frames as numpy arrays, the event log.

The format is specified in ``docs/trace-format.md`` (its constants in
``fleet_async.core.view.trace.format``) and written by ``fleet_async.core.view.trace``. The
browser viewer has its own decoder in JavaScript (``static/trace.js``); this one serves Python
users, the ``view`` command's checks and tests.
"""

from __future__ import annotations

import os
import struct
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fleet_async.core.view.trace.format import (
    HEADER,
    MAGIC,
    READABLE_VERSIONS,
    RECORD,
    YAW_SCALE,
    RecordKind,
)
from fleet_async.viewer.payloads import (
    PayloadError,
    bodies_payload,
    collisions_size,
    entries,
    frames_size,
    json_payload,
    layout_size,
    meta_payload,
)

__all__ = ["Frame", "TraceCutWarning", "TraceFormatError", "TraceReader", "check_trace"]

_FRAMES_HEADER = struct.Struct("<II")


class TraceFormatError(ValueError):
    """A file is not a trace this version can read, or one of its records is malformed.

    The message names the file, what is wrong (for a record: its number, kind and byte offset)
    and the format version (the file's, when its header could be read, and the ones this
    reader reads). It is the only error the reader raises for a file's contents.
    """


class TraceCutWarning(UserWarning):
    """A trace ends early (a killed run, a copy cut short): its readable prefix is loaded."""


@dataclass(frozen=True)
class Frame:
    """The poses of one frame.

    Attributes:
        step: The simulation step the frame shows (sim time = step * timestep).
        ids: Object ids of the frame's bodies, shape (N,) int32.
        position: World positions, metres, shape (N, 3) float32.
        yaw: Headings about +z, radians, shape (N,) float64.
        flags: Flag bits per body (moving 1, carrying 2, failed 4), shape (N,) uint8.
    """

    step: int
    ids: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    flags: np.ndarray


@dataclass(frozen=True)
class _Chunk:
    offset: int  # of the FRAMES payload
    count: int
    n: int
    layout: np.ndarray


class TraceReader:
    """Index a trace file and read its frames and events.

    A trace that ends early (a record cut short, or no end record: the run was killed, or the
    copy is incomplete) loads its readable prefix: :attr:`cut` says what is missing, and a
    :class:`TraceCutWarning` is issued (not for ``allow_unfinished``, whose file is expected
    to grow). ``strict=True`` refuses such a file instead.

    Args:
        path: The trace file.
        allow_unfinished: The file is still being written (a live run): an end that is not
            there yet is no surprise, so no warning.
        strict: Refuse a trace that ends early (TraceFormatError) instead of loading its prefix.

    Raises:
        FileNotFoundError: if ``path`` does not exist.
        TraceFormatError: for a file that is not a trace, another format version, a malformed
            record (naming its number, kind and byte), no META record before the cut, or (with
            ``strict``) one that ends early.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        allow_unfinished: bool = False,
        strict: bool = False,
    ) -> None:
        self.path = Path(path)
        self._data = np.memmap(self.path, dtype=np.uint8, mode="r") if self._size() else None
        # The same bytes as a buffer, for struct (numpy arrays are not typed as buffers).
        self._bytes: memoryview = self._data.data if self._data is not None else memoryview(b"")
        self.meta: dict[str, Any] = {}
        self.shapes: list[dict[str, Any]] = []
        self.bodies: dict[int, dict[str, Any]] = {}
        self.events: list[dict[str, Any]] = []
        self.commands: list[dict[str, Any]] = []
        """Fleet masters' commands: ``step`` (the step count when applied), ``vehicle``,
        ``command`` (JSON data, ``fleet_async.interfaces.command_from_json`` reads it)."""
        self.end: dict[str, Any] | None = None
        self.cut: str | None = None
        """Why the file ends before its end record (None for a complete trace)."""
        self._chunks: list[_Chunk] = []
        self._collisions: list[tuple[np.ndarray, ...]] = []
        self._version = self._read_header()
        self._index()
        if self.cut is not None:
            if strict:
                raise self._error(self.cut, self._version)
            if not allow_unfinished:
                warnings.warn(
                    f"{self.path}: {self.cut}; showing the readable prefix ({self.frame_count} "
                    "frames)",
                    TraceCutWarning,
                    stacklevel=2,
                )

    def _size(self) -> int:
        return self.path.stat().st_size

    def _error(self, problem: str, version: int | None = None) -> TraceFormatError:
        found = f"the file's format version is {version}; " if version is not None else ""
        return TraceFormatError(
            f"{self.path}: {problem} ({found}this fleet_async reads trace format versions "
            f"{' and '.join(map(str, READABLE_VERSIONS))})"
        )

    def _read_header(self) -> int:
        data = self._data
        if data is None or len(data) < HEADER.size:
            size = 0 if data is None else len(data)
            if size >= len(MAGIC) and bytes(data[: len(MAGIC)]) != MAGIC:  # type: ignore[index]  # size > 0
                raise self._error("not a fleet_async trace (wrong magic bytes)")
            raise self._error(
                f"truncated: {size} bytes, shorter than the {HEADER.size}-byte header"
            )
        magic, version, header_size, _ = HEADER.unpack_from(self._bytes, 0)
        if magic != MAGIC:
            raise self._error(
                f"not a fleet_async trace (magic bytes {magic!r}, expected {MAGIC!r})"
            )
        if version not in READABLE_VERSIONS:
            raise self._error(f"unsupported trace format version {version}", version)
        if not HEADER.size <= header_size <= len(data):
            raise self._error(f"bad header size {header_size}", version)
        return int(version)

    def _index(self) -> None:
        data = self._data
        assert data is not None
        offset = HEADER.unpack_from(self._bytes, 0)[2]
        layout = np.zeros(0, dtype=np.int32)
        records = 0
        while offset < len(data) and self.end is None:
            if offset + RECORD.size > len(data):
                self.cut = (
                    f"truncated: record {records} at byte {offset} has only "
                    f"{len(data) - offset} of its {RECORD.size} header bytes"
                )
                break
            kind, length = RECORD.unpack_from(self._bytes, offset)
            name = RecordKind(kind).name if kind in RecordKind._value2member_map_ else str(kind)
            start = offset + RECORD.size
            if start + length > len(data):
                self.cut = (
                    f"truncated: record {records} ({name}) at byte {offset} needs {length} "
                    f"payload bytes, the file has {len(data) - start} left"
                )
                break
            try:
                layout = self._record(kind, start, length, layout)
            except (PayloadError, ValueError, TypeError, KeyError, struct.error) as exc:
                raise self._error(
                    f"record {records} ({name}) at byte {offset}: {exc}", self._version
                ) from None
            records += 1
            offset = start + length + (-length % 4)
        if self.end is None and self.cut is None:
            self.cut = (
                f"truncated: no end record after {records} records (the run did not finish "
                "its trace: it is still running, or it stopped without stop_trace / close)"
            )
        if not self.meta:
            problem = self.cut or f"no META record in {records} records"
            raise self._error(f"{problem}; nothing to show before it (no META)", self._version)

    def _raw(self, start: int, length: int) -> bytes:
        assert self._data is not None
        return bytes(self._data[start : start + length])

    def _record(self, kind: int, start: int, length: int, layout: np.ndarray) -> np.ndarray:
        data = self._data
        assert data is not None
        if kind != RecordKind.META and not self.meta:
            raise PayloadError("a record before the META record")
        if kind == RecordKind.META:
            self.meta = meta_payload(self._raw(start, length))
        elif kind == RecordKind.BODIES:
            shapes, bodies = bodies_payload(self._raw(start, length))
            self.shapes.extend(shapes)
            for body in bodies:
                self.bodies[int(body["id"])] = body
        elif kind == RecordKind.LAYOUT:
            n = layout_size(self._bytes, start, length)
            layout = np.frombuffer(data, dtype="<i4", count=n, offset=start + 4)
        elif kind == RecordKind.FRAMES:
            count, n = frames_size(self._bytes, start, length)
            if n != len(layout):
                raise PayloadError(
                    f"it holds {n} bodies per frame, but the layout before it lists {len(layout)}"
                )
            self._chunks.append(_Chunk(start + _FRAMES_HEADER.size, count, n, layout))
        elif kind == RecordKind.EVENTS:
            for t, step, name, object_id, payload in entries(
                self._raw(start, length), "EVENTS", "events", 5
            ):
                self.events.append(
                    {"t": t, "step": step, "kind": name, "object_id": object_id, "data": payload}
                )
        elif kind == RecordKind.COLLISIONS:
            n = collisions_size(self._bytes, start, length)
            at = start + 4
            steps, a, b = (
                np.frombuffer(data, dtype="<i4", count=n, offset=at + 4 * n * i) for i in range(3)
            )
            started = np.frombuffer(data, dtype=np.uint8, count=n, offset=at + 12 * n)
            self._collisions.append((steps, a, b, started))
        elif kind == RecordKind.COMMANDS:
            for step, vehicle, command in entries(
                self._raw(start, length), "COMMANDS", "commands", 3
            ):
                self.commands.append({"step": step, "vehicle": vehicle, "command": command})
        elif kind == RecordKind.END:
            self.end = json_payload(self._raw(start, length), "END")
        return layout

    # ----- what the file holds ---------------------------------------------------------

    @property
    def version(self) -> int:
        """The file's format version."""
        return self._version

    @property
    def timestep(self) -> float:
        """Sim seconds per step."""
        return float(self.meta["timestep"])

    @property
    def frame_count(self) -> int:
        """Number of frames."""
        return sum(c.count for c in self._chunks)

    def frame_bytes(self) -> list[int]:
        """Pose bytes (positions, yaw, flags, without padding) of each FRAMES record."""
        return [c.count * c.n * 15 for c in self._chunks]

    def frames(self) -> Iterator[Frame]:
        """Every frame, in order (arrays are read-only views of the file)."""
        assert self._data is not None
        data = self._data
        for c in self._chunks:
            k, n = c.count, c.n
            steps = np.frombuffer(data, dtype="<i4", count=k, offset=c.offset)
            at = c.offset + 4 * k
            pos = np.frombuffer(data, dtype="<f4", count=3 * k * n, offset=at).reshape(k, n, 3)
            at += 12 * k * n
            yaw = np.frombuffer(data, dtype="<i2", count=k * n, offset=at).reshape(k, n)
            at += 2 * k * n + (-(2 * k * n) % 4)
            flags = np.frombuffer(data, dtype=np.uint8, count=k * n, offset=at).reshape(k, n)
            for i in range(k):
                yield Frame(
                    int(steps[i]),
                    c.layout,
                    pos[i],
                    yaw[i].astype(np.float64) * YAW_SCALE,
                    flags[i],
                )

    def collisions(self) -> dict[str, np.ndarray]:
        """Every collision start / end: ``step``, ``a``, ``b`` (object ids, ``a < b``; a pair
        whose body left the simulation ends under its id) and ``started`` (1 started, 0
        ended), in file order."""
        parts = list(zip(*self._collisions, strict=True)) if self._collisions else [[]] * 4
        names = ("step", "a", "b", "started")
        dtypes = (np.int32, np.int32, np.int32, np.uint8)
        return {
            name: (np.concatenate(arrays) if len(arrays) else np.zeros(0, dtype=dtype))
            for name, arrays, dtype in zip(names, parts, dtypes, strict=True)
        }


def check_trace(
    path: str | os.PathLike[str], *, allow_unfinished: bool = False, strict: bool = False
) -> TraceReader:
    """Open ``path`` as a trace and check every record; return the reader (its ``cut`` says
    whether the file ends early; see :class:`TraceReader`).

    Raises:
        FileNotFoundError: if the file does not exist.
        TraceFormatError: naming the file, the problem and the format version.
    """
    return TraceReader(path, allow_unfinished=allow_unfinished, strict=strict)
