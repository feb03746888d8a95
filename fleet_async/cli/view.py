"""``fleet-async view RUN.fatrace``: serve the replay viewer for a trace and open it.

The trace is checked first (a file that is not a trace, of another format version, or cut
short is an error naming the file, the problem and the version). The page is served on this
machine only (``127.0.0.1``) unless ``--host`` says otherwise; the browser is opened where
there is a display, and the address is printed either way.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import webbrowser
from pathlib import Path

from fleet_async.cli.errors import CliError
from fleet_async.viewer import TraceFormatError, check_trace
from fleet_async.viewer.server import ViewerServer

__all__ = ["add_arguments", "can_open_browser", "execute", "open_viewer"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``view`` options to ``parser``."""
    parser.add_argument("trace", metavar="RUN.fatrace", help="the trace file to replay")
    parser.add_argument("--port", type=int, default=8765, help="TCP port (default 8765; 0: any)")
    parser.add_argument(
        "--host", default="127.0.0.1", help="interface to listen on (default 127.0.0.1)"
    )
    parser.add_argument(
        "--no-browser", action="store_true", help="only print the address; do not open a browser"
    )
    parser.add_argument(
        "--follow",
        action="store_true",
        help="the trace is still being written: stream what the run appends (live view)",
    )


def can_open_browser() -> bool:
    """Whether a graphical browser can be opened here (a display on Linux / BSD)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def open_viewer(server: ViewerServer, no_browser: bool) -> None:
    """Print the address and open it in a browser when there is one."""
    print(f"fleet_async viewer: {server.trace_path} at {server.url}  (Ctrl+C to stop)", flush=True)
    if no_browser or not can_open_browser():
        return
    with contextlib.suppress(webbrowser.Error):  # the address is printed anyway
        webbrowser.open(server.url)


def _start_server(path: Path, host: str, port: int, follow: bool) -> ViewerServer:
    try:
        return ViewerServer(path, host, port, follow=follow)
    except OSError as exc:
        raise CliError(
            f"cannot listen on {host}:{port} ({exc.strerror}); pick another with --port"
        ) from exc


def execute(args: argparse.Namespace) -> int:
    """Run the ``view`` command; return the exit code (serves until Ctrl+C)."""
    path = Path(args.trace)
    try:
        check_trace(path, allow_unfinished=args.follow)
    except FileNotFoundError as exc:
        raise CliError(f"{path}: no such trace file") from exc
    except TraceFormatError as exc:
        hint = (
            "; if the run is still writing it, add --follow" if "no end record" in str(exc) else ""
        )
        raise CliError(f"{exc}{hint}") from exc
    server = _start_server(path, args.host, args.port, args.follow)
    open_viewer(server, args.no_browser)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop_serving()
    return 0
