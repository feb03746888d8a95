"""Checking a trace record's payload before the reader uses it.

Every record is checked against ``docs/trace-format.md`` before anything of it is kept: JSON
records decode as UTF-8 JSON of the documented shape (a META with a positive timestep, BODIES
with lists of shapes and of bodies with integer ids, EVENTS and COMMANDS as lists of entries of
the documented length), binary records hold the bytes their counts need. A payload that does
not is a :class:`PayloadError`, which the reader reports with the record's number, kind and
byte offset.
"""

from __future__ import annotations

import json
import math
import struct
from typing import Any

from fleet_async.core.view.trace.format import BYTES_PER_BODY_FRAME, FRAMES_HEADER, padding

__all__ = [
    "PayloadError",
    "bodies_payload",
    "collisions_size",
    "entries",
    "frames_size",
    "json_payload",
    "layout_size",
    "meta_payload",
]

_COUNT = struct.Struct("<I")


class PayloadError(ValueError):
    """A record's payload does not have the documented shape."""


def json_payload(raw: bytes, kind: str) -> dict[str, Any]:
    """The JSON object of a record.

    Raises:
        PayloadError: for bytes that are not UTF-8 JSON of an object.
    """
    try:
        value = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise PayloadError(f"the {kind} payload is not UTF-8 JSON ({exc})") from None
    if not isinstance(value, dict):
        raise PayloadError(f"the {kind} payload is JSON {type(value).__name__}, not an object")
    return value


def meta_payload(raw: bytes) -> dict[str, Any]:
    """The META record, with a finite timestep > 0."""
    meta = json_payload(raw, "META")
    timestep = meta.get("timestep")
    if (
        isinstance(timestep, bool)
        or not isinstance(timestep, (int, float))
        or not math.isfinite(timestep)
        or timestep <= 0
    ):
        raise PayloadError(f"META: timestep {timestep!r} is not a number of seconds > 0")
    return meta


def bodies_payload(raw: bytes) -> tuple[list[Any], list[dict[str, Any]]]:
    """(shapes, bodies) of a BODIES record; every body a mapping with an integer id."""
    value = json_payload(raw, "BODIES")
    shapes, bodies = value.get("shapes"), value.get("bodies")
    if not isinstance(shapes, list) or not isinstance(bodies, list):
        raise PayloadError("BODIES: 'shapes' and 'bodies' must be lists")
    for body in bodies:
        if (
            not isinstance(body, dict)
            or isinstance(body.get("id"), bool)
            or not isinstance(body.get("id"), int)
        ):
            raise PayloadError(f"BODIES: a body without an integer id: {str(body)[:80]}")
    return shapes, bodies


def entries(raw: bytes, kind: str, key: str, width: int) -> list[list[Any]]:
    """The ``key`` list of an EVENTS or COMMANDS record, each entry a list of ``width``."""
    value = json_payload(raw, kind).get(key)
    if not isinstance(value, list) or not all(
        isinstance(e, list) and len(e) == width for e in value
    ):
        raise PayloadError(f"{kind}: {key!r} must be a list of {width}-item lists")
    return value


def _count(data: memoryview, start: int, length: int, kind: str) -> int:
    if length < _COUNT.size:
        raise PayloadError(f"{kind}: {length} payload bytes, no count")
    return int(_COUNT.unpack_from(data, start)[0])


def layout_size(data: memoryview, start: int, length: int) -> int:
    """N of a LAYOUT record, checked against its length."""
    n = _count(data, start, length, "LAYOUT")
    if 4 + 4 * n > length:
        raise PayloadError(f"LAYOUT: {n} ids need {4 + 4 * n} bytes, the record has {length}")
    return n


def frames_size(data: memoryview, start: int, length: int) -> tuple[int, int]:
    """(K, N) of a FRAMES record, checked against its length."""
    if length < FRAMES_HEADER.size:
        raise PayloadError(f"FRAMES: {length} payload bytes, shorter than its header")
    k, n = FRAMES_HEADER.unpack_from(data, start)
    need = FRAMES_HEADER.size + 4 * k + (BYTES_PER_BODY_FRAME - 1) * k * n + padding(2 * k * n)
    need += k * n
    if need > length:
        raise PayloadError(
            f"FRAMES: {k} frames of {n} bodies need {need} bytes, the record has {length}"
        )
    return int(k), int(n)


def collisions_size(data: memoryview, start: int, length: int) -> int:
    """M of a COLLISIONS record, checked against its length."""
    m = _count(data, start, length, "COLLISIONS")
    if 4 + 13 * m > length:
        raise PayloadError(
            f"COLLISIONS: {m} entries need {4 + 13 * m} bytes, the record has {length}"
        )
    return m
