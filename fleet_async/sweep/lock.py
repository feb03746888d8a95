"""One sweep at a time on a table: an OS lock that dies with the process holding it.

Two sweeps writing the same ``--out`` would both run everything, and the one whose file was
replaced by the other's rewrite would keep appending to a deleted file. ``run_sweep`` so takes
an exclusive ``flock`` on ``<out>.lock`` (created beside the table, holding the holder's pid)
for as long as it writes, and a second sweep on the same table is refused at once, naming the
holder. The kernel drops the lock when its holder exits, however it exits (``kill -9``
included), so a rerun after a crash resumes without anything to clean up. The lock file is
removed when the sweep ends. Where ``fcntl`` does not exist (Windows), no lock is taken.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

try:
    import fcntl
except ImportError:  # Windows: no flock; sweeps there are not guarded
    fcntl = None  # type: ignore[assignment]

__all__ = ["SweepLockedError", "TableLock"]


class SweepLockedError(RuntimeError):
    """Another sweep is writing the same table."""


class TableLock:
    """The lock of the table at ``path`` (``<path>.lock``), taken by :meth:`acquire`.

    Args:
        path: The table the lock guards.
    """

    def __init__(self, path: str | Path) -> None:
        self.table = Path(path)
        self.path = self.table.with_name(self.table.name + ".lock")
        self._fd: int | None = None

    def acquire(self) -> None:
        """Take the lock, or refuse at once.

        Raises:
            SweepLockedError: while another process holds it, naming that process.
        """
        if fcntl is None or self._fd is not None:
            return
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 64).decode(errors="replace").strip() or "?"
                os.close(fd)
                raise SweepLockedError(
                    f"{self.table} is being written by another sweep (process {holder}; its "
                    f"lock: {self.path}); wait for it to finish, or write to another file "
                    "with --out"
                ) from None
            try:  # the holder before us may have removed the file we opened: try again
                same = os.fstat(fd).st_ino == os.stat(self.path).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd = fd

    def release(self) -> None:
        """Remove the lock file and let go (nothing if not held)."""
        if self._fd is None:
            return
        with contextlib.suppress(FileNotFoundError):
            self.path.unlink()  # while held: whoever opened it retries on the new file
        os.close(self._fd)
        self._fd = None
