"""``fleet-async view RUN.fatrace``: serve the replay viewer for a trace and open it.

The trace is checked first (a file that is not a trace, of another format version, or with a
malformed record is an error naming the file, the problem and the version; one that ends early,
the trace of a killed run, is shown up to where it ends, with a warning). The page is served on this
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

__all__ = ["add_arguments", "can_open_browser", "execute", "open_viewer", "warn"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``view`` options to ``parser``."""
    parser.add_argument("trace", metavar="RUN.fatrace", help="the trace file to replay")
    parser.add_argument("--port", type=int, default=8765, help="TCP port (default 8765; 0: any)")
    parser.add_argument(
        "--host",
        default="127.0.0.1",
        help="interface to listen on (default 127.0.0.1, this machine only; 0.0.0.0: every "
        "interface, with a warning)",
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


def warn(message: str) -> None:
    """Print a warning for the user on stderr (the server's notices, a cut trace)."""
    print(f"fleet-async: warning: {message}", file=sys.stderr, flush=True)


def open_viewer(server: ViewerServer, no_browser: bool) -> None:
    """Print the address (the one other machines use when listening on every interface, with
    a warning) and open it in a browser when there is one."""
    host, port = server.listening
    public = server.public_url
    if public is not None:
        print(
            f"fleet_async viewer: {server.trace_path} on every interface ({host}:{port}): "
            f"{public} from other machines, {server.url} here  (Ctrl+C to stop)",
            flush=True,
        )
        warn(
            f"the viewer listens on {host}:{port}, every interface: anyone who can reach this "
            "machine on that port can read the trace; use --host 127.0.0.1 to keep it local"
        )
    else:
        print(
            f"fleet_async viewer: {server.trace_path} at {server.url}  (Ctrl+C to stop)",
            flush=True,
        )
    if no_browser or not can_open_browser():
        return
    with contextlib.suppress(webbrowser.Error):  # the address is printed anyway
        webbrowser.open(server.url)


def _start_server(path: Path, host: str, port: int, follow: bool) -> ViewerServer:
    try:
        return ViewerServer(path, host, port, follow=follow, notice=warn)
    except OSError as exc:
        raise CliError(
            f"cannot listen on {host}:{port} ({exc.strerror}); pick another with --port"
        ) from exc


def execute(args: argparse.Namespace) -> int:
    """Run the ``view`` command; return the exit code (serves until Ctrl+C)."""
    path = Path(args.trace)
    try:
        reader = check_trace(path, allow_unfinished=True)
    except FileNotFoundError as exc:
        raise CliError(f"{path}: no such trace file") from exc
    except TraceFormatError as exc:
        raise CliError(str(exc)) from exc
    if reader.cut is not None and not args.follow:
        hint = "; if the run is still writing it, add --follow" if reader.end is None else ""
        warn(
            f"{path}: {reader.cut}; the viewer shows the readable prefix "
            f"({reader.frame_count} frames){hint}"
        )
    server = _start_server(path, args.host, args.port, args.follow)
    open_viewer(server, args.no_browser)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop_serving()
    return 0
