"""A small local HTTP server for the viewer page and one trace (standard library only).

Routes: ``/`` the page, its scripts (``/trace.js`` ``/palette.js`` ``/timeline.js``
``/panel.js`` ``/vehicle.js`` ``/render.js`` ``/viewer.js``) and ``/viewer.css`` (package data
in ``static/``), ``/trace`` the trace file, streamed in chunks. With
``follow=True`` (a run in progress, ``fleet-async run --view``) ``/trace`` keeps streaming what
the writer appends until the trace's end record has been sent, so the page shows a live run.
"""

from __future__ import annotations

import html
import logging
import os
import threading
import time
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from pathlib import Path
from typing import Any, BinaryIO

from fleet_async.core.view.trace.format import HEADER, RECORD, RecordKind

__all__ = ["ViewerServer"]

logger = logging.getLogger(__name__)

_ASSETS = {
    "/trace.js": "text/javascript",
    "/palette.js": "text/javascript",
    "/timeline.js": "text/javascript",
    "/panel.js": "text/javascript",
    "/vehicle.js": "text/javascript",
    "/render.js": "text/javascript",
    "/viewer.js": "text/javascript",
    "/viewer.css": "text/css",
}
_CHUNK = 1 << 20
_POLL_SECONDS = 0.1


def _asset(name: str) -> bytes:
    return resources.files("fleet_async.viewer").joinpath("static").joinpath(name).read_bytes()


class _RecordWalker:
    """Follows record boundaries in the bytes sent so far, to notice the end record."""

    def __init__(self) -> None:
        self.next_record = HEADER.size
        self.finished = False

    def advance(self, f: BinaryIO, sent: int) -> None:
        here = f.tell()
        while not self.finished and self.next_record + RECORD.size <= sent:
            f.seek(self.next_record)
            kind, length = RECORD.unpack(f.read(RECORD.size))
            end = self.next_record + RECORD.size + length + (-length % 4)
            if end > sent:
                break
            self.finished = kind == RecordKind.END
            self.next_record = end
        f.seek(here)


class _Handler(BaseHTTPRequestHandler):
    server: ViewerServer

    def log_message(self, format: str, *args: Any) -> None:  # the stdlib names it so
        logger.debug("%s - %s", self.address_string(), format % args)

    def do_GET(self) -> None:
        path = self.path.split("?", 1)[0]
        try:
            if path in ("/", "/index.html"):
                name = html.escape(self.server.trace_path.name)
                page = _asset("index.html").decode("utf-8").replace("{{TRACE_NAME}}", name)
                self._send_bytes(page.encode("utf-8"), "text/html; charset=utf-8")
            elif path in _ASSETS:
                self._send_bytes(_asset(path[1:]), _ASSETS[path] + "; charset=utf-8")
            elif path == "/trace":
                self._send_trace()
            else:
                self.send_error(HTTPStatus.NOT_FOUND, f"no such page: {path}")
        except (BrokenPipeError, ConnectionResetError):
            pass  # the page went away

    def _send_bytes(self, body: bytes, content_type: str) -> None:
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def _send_trace(self) -> None:
        server = self.server
        try:
            f = open(server.trace_path, "rb")  # noqa: SIM115  # closed below
        except OSError as exc:
            self.send_error(HTTPStatus.NOT_FOUND, f"{server.trace_path}: {exc.strerror}")
            return
        with f:
            self.send_response(HTTPStatus.OK)
            self.send_header("Content-Type", "application/octet-stream")
            self.send_header("Cache-Control", "no-store")
            if server.follow:
                self.send_header("X-Trace-Live", "1")
            else:
                self.send_header("Content-Length", str(os.fstat(f.fileno()).st_size))
            self.end_headers()
            self._stream(f)

    def _stream(self, f: BinaryIO) -> None:
        server, walker, sent = self.server, _RecordWalker(), 0
        while True:
            chunk = f.read(_CHUNK)
            if chunk:
                self.wfile.write(chunk)
                sent += len(chunk)
                if server.follow:
                    walker.advance(f, sent)
                continue
            self.wfile.flush()
            if not server.follow or walker.finished or server.stopping.is_set():
                return
            time.sleep(_POLL_SECONDS)  # the writer has not appended more yet


class ViewerServer(ThreadingHTTPServer):
    """Serves the viewer page and ``trace_path`` on ``host:port`` (0: a free port).

    Args:
        trace_path: The trace file.
        host: Interface to listen on (default: this machine only).
        port: TCP port; 0 picks a free one (see :attr:`url`).
        follow: Keep streaming what is appended to the file until its end record (live runs).
    """

    daemon_threads = True

    def __init__(
        self,
        trace_path: str | os.PathLike[str],
        host: str = "127.0.0.1",
        port: int = 0,
        *,
        follow: bool = False,
    ) -> None:
        self.trace_path = Path(trace_path)
        self.follow = follow
        self.stopping = threading.Event()
        super().__init__((host, port), _Handler)

    @property
    def url(self) -> str:
        """The page's address."""
        host, port = self.server_address[:2]
        shown = host if isinstance(host, str) else host.decode()
        if shown in ("0.0.0.0", ""):
            shown = "127.0.0.1"
        return f"http://{shown}:{port}/"

    def start_background(self) -> threading.Thread:
        """Serve from a daemon thread; :meth:`stop` ends it."""
        thread = threading.Thread(target=self.serve_forever, name="fleet-async-viewer", daemon=True)
        thread.start()
        return thread

    def stop(self) -> None:
        """Stop a :meth:`start_background` server (live streams end at their next poll)."""
        self.stopping.set()
        self.shutdown()
        self.server_close()

    def stop_serving(self) -> None:
        """After ``serve_forever`` returned in this thread: end live streams, close the socket."""
        self.stopping.set()
        self.server_close()
