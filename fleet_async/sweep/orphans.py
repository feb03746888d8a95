"""Pool workers do not outlive the sweep that started them.

A sweep's parent killed with ``kill -9`` runs no cleanup, and its pool's workers would go on
running (and computing rows nobody writes) until their runs end. Each worker so watches its
parent from its first moment: on Linux the kernel is asked to kill it when the parent dies
(``PR_SET_PDEATHSIG``); everywhere, a daemon thread checks every half second that its parent
is still the process that started it, and exits at once when it is not. Workers also ignore
Ctrl+C, which the sweep handles (no new run starts, the ones in progress finish).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading

__all__ = ["WATCH_PERIOD_S", "init_worker"]

WATCH_PERIOD_S = 0.5
_PR_SET_PDEATHSIG = 1


def _watch(parent: int) -> None:
    event = threading.Event()
    while not event.wait(WATCH_PERIOD_S):
        if os.getppid() != parent:
            os._exit(1)  # the sweep is gone: nobody will write this run's row


def init_worker(parent: int) -> None:
    """Ignore Ctrl+C and exit when the process ``parent`` (the sweep) dies."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:  # died before the request was made
        os._exit(1)
    threading.Thread(target=_watch, args=(parent,), name="sweep-parent-watch", daemon=True).start()
