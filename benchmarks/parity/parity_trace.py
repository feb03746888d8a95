"""Trace recorder for the parity scripts (imported by scripts on both sides).

Plain Python with no dependency on either simulator, so the same file serves the incumbent's
venv and ours. A script fills a :class:`Trace` with named probes and calls :meth:`Trace.dump`,
which prints one marker line with the JSON on stdout (PyBullet writes to stdout too, so the
harness looks for the marker rather than parsing the whole stream).
"""

from __future__ import annotations

import contextlib
import enum
import json
import math
import os
import sys
import traceback
from collections.abc import Iterator, Mapping
from typing import Any

MARKER = "@@PARITY_TRACE@@ "
ROUND = 6


def plain(value: Any) -> Any:
    """Turn ``value`` into JSON-able data: floats rounded, enums by value, arrays as lists."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, enum.Enum):
        return plain(value.value)
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        if math.isnan(value) or math.isinf(value):
            return repr(value)
        rounded = round(value, ROUND)
        return 0.0 if rounded == 0 else rounded
    if hasattr(value, "tolist") and not isinstance(value, type):  # numpy arrays and scalars
        return plain(value.tolist())
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        items = [plain(v) for v in value]
        return sorted(items, key=repr) if isinstance(value, (set, frozenset)) else items
    return f"<{type(value).__name__}>"


def error_text(exc: BaseException) -> str:
    """One line naming the exception, its message and the innermost frame of the script."""
    frames = traceback.extract_tb(exc.__traceback__)
    where = ""
    for frame in reversed(frames):
        if frame.filename == sys.argv[0] or frame.filename.endswith(os.path.basename(sys.argv[0])):
            where = f" (script line {frame.lineno})"
            break
    message = str(exc).splitlines()[0] if str(exc) else ""
    return f"{type(exc).__name__}: {message}{where}"


class Snapshot(dict):
    """A dict that converts values with :func:`plain` when they are stored, so a value the
    simulator later mutates in place (a cached pose list, say) is recorded as it was."""

    def __setitem__(self, key: str, value: Any) -> None:
        super().__setitem__(key, plain(value))

    def update(self, *args: Any, **kwargs: Any) -> None:  # type: ignore[override]
        for key, value in dict(*args, **kwargs).items():
            self[key] = value


class Trace:
    """Named probes of one scenario; each probe's failure is recorded, not fatal."""

    def __init__(self) -> None:
        self.data: dict[str, Any] = {}

    def __setitem__(self, key: str, value: Any) -> None:
        self.data[key] = plain(value)

    def __getitem__(self, key: str) -> Any:
        return self.data[key]

    @contextlib.contextmanager
    def probe(self, name: str) -> Iterator[dict[str, Any]]:
        """Record the dict the block fills under ``name``; an exception becomes ``{"error"}``."""
        out: dict[str, Any] = Snapshot()
        try:
            yield out
        except Exception as exc:
            out["error"] = error_text(exc)
        self.data[name] = dict(out)

    def dump(self) -> None:
        """Print the trace (with the import notes of the fleet_async shim, if any)."""
        shim = sys.modules.get("parity_shim")
        notes = getattr(shim, "NOTES", None)
        if notes:
            self.data["_import_notes"] = plain(notes)
        sys.stdout.flush()
        print(MARKER + json.dumps(self.data, sort_keys=True), flush=True)


def call_safely(fn: Any, *args: Any, **kwargs: Any) -> Any:
    """Return ``fn(*args, **kwargs)``, or ``{"error": ...}`` if it raises."""
    try:
        return plain(fn(*args, **kwargs))
    except Exception as exc:
        return {"error": error_text(exc)}


def angle(rad: float, digits: int = 3) -> float:
    """An angle in (-pi, pi], rounded, so that -pi and pi (the same heading) compare equal."""
    wrapped = math.atan2(math.sin(rad), math.cos(rad))
    if wrapped <= -math.pi + 10 ** -(digits + 1):
        wrapped = math.pi
    return round(wrapped, digits)
