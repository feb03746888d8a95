"""The trace file format: magic, version, record kinds, frame flags (``docs/trace-format.md``).

Shared by the writer (``writer.py``) and the readers (``fleet_async.viewer``). A file is a
16-byte header followed by length-prefixed records; poses are stored per frame as structure of
arrays over the frame's bodies: float32 positions, an int16 yaw and a flag byte, 15 bytes per
body per frame.

Yaw, not a quaternion: the viewer is top-down, and the heading is what it draws. A robot that
tilts (an arm's link, a carried box) is drawn by its heading alone; the trace is not a
checkpoint and does not restore 3D orientation.
"""

from __future__ import annotations

import math
import struct
from enum import IntEnum

__all__ = [
    "BYTES_PER_BODY_FRAME",
    "FLAG_CARRYING",
    "FLAG_FAILED",
    "FLAG_MOVING",
    "FORMAT_VERSION",
    "FRAMES_HEADER",
    "HEADER",
    "MAGIC",
    "READABLE_VERSIONS",
    "RECORD",
    "YAW_SCALE",
    "RecordKind",
    "padding",
]

MAGIC = b"FLEETTRC"
"""First 8 bytes of every trace file."""
FORMAT_VERSION = 2
"""Version of the file format this package writes."""
READABLE_VERSIONS = (1, 2)
"""Versions the readers accept (2 added the COMMANDS record; a version 1 file has none)."""
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
"""Flag bit: the body's position or yaw differs from the frame before."""
FLAG_CARRYING = 2
"""Flag bit: something is attached to the body."""
FLAG_FAILED = 4
"""Flag bit: the body's last action failed (cleared when its next action starts)."""


class RecordKind(IntEnum):
    """Kinds of record in a trace file (readers skip kinds they do not know)."""

    META = 1
    BODIES = 2
    LAYOUT = 3
    FRAMES = 4
    EVENTS = 5
    COLLISIONS = 6
    END = 7
    COMMANDS = 8


def padding(n: int) -> int:
    """Zero bytes that follow ``n`` payload bytes so the next record starts 4-aligned."""
    return (-n) % 4
