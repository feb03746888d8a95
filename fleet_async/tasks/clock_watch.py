"""The watchdog thread: a mission that runs Python code without awaiting holds the clock.

The driver's own watchdog (a task of the host loop) sees a mission that holds the clock on a
non-sim await; it cannot see one that never returns to the loop at all (a ``while`` loop
without an await, a long computation). This thread samples which mission is running and how
many resumptions the kernel has made: the same mission in the same resumption across samples
has run without parking since the first of them. After a second it warns, naming the mission
and the line it is on; after the watchdog's limit it raises MissionStalledError inside the
run's thread (CPython's asynchronous exception), which fails that mission.
"""

from __future__ import annotations

import ctypes
import logging
import sys
import threading
import time
import warnings
from typing import TYPE_CHECKING, Any

from fleet_async.tasks.errors import MissionStalledError

if TYPE_CHECKING:
    from fleet_async.tasks.kernel import Kernel

__all__ = ["ClockWatch", "where_running"]

logger = logging.getLogger(__name__)


class ClockWatch:
    """Watches ``kernel.current`` from a daemon thread while a run drives its missions.

    Args:
        kernel: The run's kernel.
        warn_after: Wall seconds of running without a park before one warning.
        fail_after: Wall seconds before MissionStalledError is raised in the run's thread.
    """

    def __init__(self, kernel: Kernel, warn_after: float, fail_after: float) -> None:
        self._kernel = kernel
        self._warn_after = warn_after
        self._fail_after = fail_after
        self._run_thread = threading.get_ident()
        self._stop = threading.Event()
        self._thread = threading.Thread(
            target=self._watch, name="fleet_async clock watch", daemon=True
        )

    def __enter__(self) -> ClockWatch:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def _watch(self) -> None:
        kernel = self._kernel
        period = min(0.25, self._fail_after / 4)
        seen: tuple[Any, int] | None = None
        since = 0.0
        warned = failed = False
        while not self._stop.wait(period):
            mission, resumes = kernel.current, kernel.resumes
            if mission is None or (mission, resumes) != seen:
                seen = None if mission is None else (mission, resumes)
                since, warned, failed = time.perf_counter(), False, False
                continue
            held = time.perf_counter() - since
            if failed:
                continue
            if not warned and held >= self._warn_after and self._fail_after > self._warn_after:
                warned = True
                warnings.warn(self._message(mission.name, held), stacklevel=1)
            if held > self._fail_after:
                failed = True
                message = self._message(mission.name, held) + (
                    f" (the watchdog allows {self._fail_after} s)"
                )
                if not _raise_in(self._run_thread, message):
                    logger.error(message)

    def _message(self, name: str, held: float) -> str:
        return (
            f"mission {name!r} has held the simulation clock for {held:.1f} s of wall time "
            f"running Python code without awaiting, {where_running(self._run_thread)}: "
            "missions share one clock, so code that loops or computes for long holds every "
            "other mission; await sim time in the loop (await sim.sleep(...)), or raise "
            "fleet_async.run(..., watchdog=...) for a long computation"
        )


def where_running(thread_id: int) -> str:
    """``at file:line in function`` of what ``thread_id`` runs now (its innermost frame)."""
    # The only way to see another thread's stack; read-only, and only when warning.
    frame = sys._current_frames().get(thread_id)  # noqa: SLF001
    if frame is None:
        return "at an unknown line"
    code = frame.f_code
    return f"at {code.co_filename}:{frame.f_lineno} in {code.co_name}"


def _raise_in(thread_id: int, message: str) -> bool:
    """Raise MissionStalledError(message) in ``thread_id`` at its next bytecode; return
    whether the interpreter supports it."""
    set_async_exc = getattr(getattr(ctypes, "pythonapi", None), "PyThreadState_SetAsyncExc", None)
    if set_async_exc is None:  # pragma: no cover  # not CPython
        return False

    def __init__(self: MissionStalledError) -> None:
        MissionStalledError.__init__(self, message)

    stalled = type("MissionStalledError", (MissionStalledError,), {"__init__": __init__})
    set_async_exc(ctypes.c_ulong(thread_id), ctypes.py_object(stalled))
    return True
