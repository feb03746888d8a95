"""Keeping PyBullet's C-level output off the terminal while Python's output stays on it.

PyBullet's C code writes straight to file descriptors 1 and 2: a build banner when the module is
imported, and in GUI mode some fifty lines of OpenGL and thread chatter when it connects and
disconnects. Python's ``print`` cannot be told apart from it at the descriptor, so
:func:`native_output_hidden` points descriptors 1 and 2 at a temporary file and gives Python's
``sys.stdout`` / ``sys.stderr`` private duplicates of the terminal's descriptors for the
duration: what Python prints still shows, what C prints is kept aside (``HiddenOutput.text``).

Only the command line does this (``fleet-async ... --verbose`` turns it off); importing the
library never touches the process's descriptors.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
import tempfile
from collections.abc import Iterator
from typing import TextIO

__all__ = ["HiddenOutput", "native_output_hidden"]


class HiddenOutput:
    """What C code wrote while hidden (read it after the ``with`` block ends)."""

    def __init__(self) -> None:
        self.text = ""

    @property
    def line_count(self) -> int:
        """Non-empty lines hidden, not counting PyBullet's build banner."""
        return sum(
            1
            for line in self.text.splitlines()
            if line.strip() and not line.startswith("pybullet build time:")
        )


def _flush_c_stdio() -> None:
    """Flush the C library's stdio buffers, so their bytes go where the descriptor points now."""
    # No C library by that name (e.g. on Windows): nothing to flush.
    with contextlib.suppress(OSError, AttributeError, TypeError):
        ctypes.CDLL(None).fflush(None)


def _fileno(stream: TextIO | None) -> int | None:
    try:
        return None if stream is None else stream.fileno()
    except (OSError, ValueError, AttributeError):  # pytest's capture, a closed stream, ...
        return None


@contextlib.contextmanager
def native_output_hidden(enabled: bool = True) -> Iterator[HiddenOutput]:
    """Hide what C code writes to descriptors 1 and 2 inside the block.

    Python streams that write to those descriptors (the usual ``sys.stdout`` and
    ``sys.stderr``) are swapped for streams on duplicates of the original descriptors, so the
    user still sees them, including ``isatty()``. Streams that are not on descriptor 1 or 2
    (pytest's capture, a ``StringIO``) are left alone.

    Args:
        enabled: False makes this a no-op (``--verbose``).

    Yields:
        A HiddenOutput whose ``text`` is filled in when the block exits.
    """
    hidden = HiddenOutput()
    if not enabled:
        yield hidden
        return
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError, AttributeError):
            stream.flush()
    _flush_c_stdio()
    try:
        saved = {fd: os.dup(fd) for fd in (1, 2)}
    except OSError:  # a descriptor is closed: nothing to protect
        yield hidden
        return
    sink = tempfile.TemporaryFile()  # noqa: SIM115  # closed in the finally block below
    swapped: list[tuple[str, TextIO, TextIO]] = []
    try:
        for fd in (1, 2):
            os.dup2(sink.fileno(), fd)
        for name, fd in (("stdout", 1), ("stderr", 2)):
            original: TextIO = getattr(sys, name)
            replacement: TextIO
            if _fileno(original) != fd:
                continue
            replacement = open(  # noqa: SIM115  # closed when the block ends
                os.dup(saved[fd]),
                "w",
                buffering=1,
                encoding=original.encoding,
                errors=original.errors,
            )
            setattr(sys, name, replacement)
            swapped.append((name, original, replacement))
        yield hidden
    finally:
        for name, original, replacement in reversed(swapped):
            with contextlib.suppress(OSError, ValueError):
                replacement.flush()
            setattr(sys, name, original)
            with contextlib.suppress(OSError, ValueError):
                replacement.close()
        _flush_c_stdio()
        for fd, copy in saved.items():
            os.dup2(copy, fd)
            os.close(copy)
        sink.seek(0)
        hidden.text = sink.read().decode("utf-8", errors="replace")
        sink.close()
