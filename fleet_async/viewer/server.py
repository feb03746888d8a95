"""A small local HTTP server for the viewer page and one trace (standard library only).

Routes: ``/`` the page, its scripts (``/trace.js`` ``/palette.js`` ``/timeline.js``
``/panel.js`` ``/vehicle.js`` ``/traffic.js`` ``/render.js`` ``/viewer.js``) and
``/viewer.css`` (package data in ``static/``), ``/trace`` the trace file, streamed in chunks. With
``follow=True`` (a run in progress, ``fleet-async run --view``) ``/trace`` keeps streaming what
the writer appends until the trace's end record has been sent, so the page shows a live run;
when the file stops growing for ``stale_after`` seconds without its end record, the server says
so (the writer was killed, or is stuck) and keeps waiting.

What it guards against (docs/security.md): the trace file is opened once, when the server
starts, and every request reads that open file (``os.pread``), so swapping the path for a
symlink afterwards serves nothing else; requests whose ``Host`` header is not this machine
are refused (DNS rebinding, ``addresses.py``); a connection idle for ``timeout`` seconds is
closed, and at most ``max_connections`` are served at once (the next get 503), so idle sockets
cannot pile up threads.
"""

from __future__ import annotations

import html
import logging
import os
import threading
import time
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from pathlib import Path
from typing import Any

from fleet_async.core.view.trace.format import HEADER, RECORD, RecordKind
from fleet_async.viewer.addresses import host_allowed, is_wildcard, outward_address, url_for

__all__ = ["ViewerServer"]

logger = logging.getLogger(__name__)

_ASSETS = {
    "/trace.js": "text/javascript",
    "/palette.js": "text/javascript",
    "/timeline.js": "text/javascript",
    "/panel.js": "text/javascript",
    "/vehicle.js": "text/javascript",
    "/traffic.js": "text/javascript",
    "/render.js": "text/javascript",
    "/viewer.js": "text/javascript",
    "/viewer.css": "text/css",
}
_CHUNK = 1 << 20
_POLL_SECONDS = 0.1
_BUSY = b"HTTP/1.0 503 Service Unavailable\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"


def _asset(name: str) -> bytes:
    return resources.files("fleet_async.viewer").joinpath("static").joinpath(name).read_bytes()


class _RecordWalker:
    """Follows record boundaries in the bytes sent so far, to notice the end record."""

    def __init__(self) -> None:
        self.next_record = HEADER.size
        self.finished = False

    def advance(self, fd: int, sent: int) -> None:
        while not self.finished and self.next_record + RECORD.size <= sent:
            kind, length = RECORD.unpack(os.pread(fd, RECORD.size, self.next_record))
            end = self.next_record + RECORD.size + length + (-length % 4)
            if end > sent:
                break
            self.finished = kind == RecordKind.END
            self.next_record = end


class _Handler(BaseHTTPRequestHandler):
    server: ViewerServer

    def setup(self) -> None:
        super().setup()
        # Reading a request, and writing to a page that stopped reading, give up after this.
        self.connection.settimeout(self.server.timeout_s)

    def log_message(self, format: str, *args: Any) -> None:  # the stdlib names it so
        logger.debug("%s - %s", self.address_string(), format % args)

    def do_GET(self) -> None:
        path = self.path.split("?", 1)[0]
        try:
            if not host_allowed(self.headers.get("Host"), self.server.allowed_hosts):
                self.send_error(
                    HTTPStatus.FORBIDDEN,
                    f"Host {self.headers.get('Host')!r} is not this viewer; open {self.server.url}",
                )
            elif path in ("/", "/index.html"):
                name = html.escape(self.server.trace_path.name)
                page = _asset("index.html").decode("utf-8").replace("{{TRACE_NAME}}", name)
                self._send_bytes(page.encode("utf-8"), "text/html; charset=utf-8")
            elif path in _ASSETS:
                self._send_bytes(_asset(path[1:]), _ASSETS[path] + "; charset=utf-8")
            elif path == "/trace":
                self._send_trace()
            else:
                self.send_error(HTTPStatus.NOT_FOUND, f"no such page: {path}")
        except (BrokenPipeError, ConnectionResetError, TimeoutError):
            pass  # the page went away, or stopped reading

    def _send_bytes(self, body: bytes, content_type: str) -> None:
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def _send_trace(self) -> None:
        fd = self.server.open_trace()
        if fd is None:
            self.send_error(HTTPStatus.SERVICE_UNAVAILABLE, "the viewer is stopping")
            return
        try:
            self._send_trace_from(fd)
        finally:
            os.close(fd)

    def _send_trace_from(self, fd: int) -> None:
        server = self.server
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "application/octet-stream")
        self.send_header("Cache-Control", "no-store")
        if server.follow:
            self.send_header("X-Trace-Live", "1")
        else:
            self.send_header("Content-Length", str(os.fstat(fd).st_size))
        self.end_headers()
        self._stream(fd)

    def _stream(self, fd: int) -> None:
        server, walker, sent = self.server, _RecordWalker(), 0
        size = None if server.follow else os.fstat(fd).st_size
        grew = time.monotonic()
        said_stale = False
        while True:
            want = _CHUNK if size is None else min(_CHUNK, size - sent)
            chunk = os.pread(fd, want, sent) if want > 0 else b""
            if chunk:
                self.wfile.write(chunk)
                sent += len(chunk)
                grew = time.monotonic()
                if server.follow:
                    walker.advance(fd, sent)
                continue
            self.wfile.flush()
            if not server.follow or walker.finished or server.stopping.is_set():
                return
            if not said_stale and time.monotonic() - grew > server.stale_after:
                said_stale = True
                server.notice(
                    f"{server.trace_path} has not grown for {server.stale_after:g} s and has "
                    "no end record: its writer seems to have stopped (a killed run?); the "
                    "viewer shows what it holds and keeps waiting"
                )
            time.sleep(_POLL_SECONDS)  # the writer has not appended more yet


class ViewerServer(ThreadingHTTPServer):
    """Serves the viewer page and ``trace_path`` on ``host:port`` (0: a free port).

    Args:
        trace_path: The trace file (opened here, once; see the module's docstring).
        host: Interface to listen on (default: this machine only).
        port: TCP port; 0 picks a free one (see :attr:`url`).
        follow: Keep streaming what is appended to the file until its end record (live runs).
        timeout: Seconds a connection may sit idle (no request, or a page not reading).
        max_connections: Connections served at once; more are answered 503.
        stale_after: With ``follow``: seconds without growth before :attr:`notice` is told.
        allowed_hosts: Names besides IP addresses, localhost and this machine's own that the
            ``Host`` header may carry (a DNS name of this machine, say).
        notice: Where warnings for the user go (default: this module's logger).

    Raises:
        OSError: if the trace cannot be opened or the address cannot be listened on.
    """

    daemon_threads = True

    def __init__(
        self,
        trace_path: str | os.PathLike[str],
        host: str = "127.0.0.1",
        port: int = 0,
        *,
        follow: bool = False,
        timeout: float = 10.0,
        max_connections: int = 32,
        stale_after: float = 30.0,
        allowed_hosts: tuple[str, ...] = (),
        notice: Callable[[str], None] | None = None,
    ) -> None:
        for name, value in (
            ("timeout", timeout),
            ("max_connections", max_connections),
            ("stale_after", stale_after),
        ):
            if not (isinstance(value, (int, float)) and value > 0):
                raise ValueError(f"ViewerServer.{name}: expected a number > 0, got {value!r}")
        self.trace_path = Path(trace_path)
        self._trace_fd = os.open(self.trace_path, os.O_RDONLY)
        self._fd_lock = threading.Lock()
        self.follow = follow
        self.timeout_s = float(timeout)
        self.stale_after = float(stale_after)
        self.allowed_hosts = tuple(allowed_hosts)
        self.notice = notice or logger.warning
        self.stopping = threading.Event()
        self._slots = threading.BoundedSemaphore(int(max_connections))
        try:
            super().__init__((host, port), _Handler)
        except OSError:
            os.close(self._trace_fd)
            raise

    @property
    def listening(self) -> tuple[str, int]:
        """(host, port) the socket is bound to."""
        host, port = self.server_address[:2]
        return (host if isinstance(host, str) else host.decode()), int(port)

    @property
    def url(self) -> str:
        """The page's address from this machine."""
        host, port = self.listening
        return url_for("127.0.0.1" if is_wildcard(host) else host, port)

    @property
    def public_url(self) -> str | None:
        """On every interface: the address other machines use (else None)."""
        host, port = self.listening
        return url_for(outward_address(), port) if is_wildcard(host) else None

    def process_request(self, request: Any, client_address: Any) -> None:
        """Serve on a thread of its own while a slot is free; else answer 503 and close."""
        if not self._slots.acquire(blocking=False):
            try:
                request.settimeout(1.0)
                request.sendall(_BUSY)
            except OSError:
                pass
            self.shutdown_request(request)
            return
        try:
            super().process_request(request, client_address)
        except BaseException:
            self._slots.release()
            raise

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        """The stdlib's, then the connection's slot is free again."""
        try:
            super().process_request_thread(request, client_address)
        finally:
            self._slots.release()

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

    def open_trace(self) -> int | None:
        """A descriptor of the trace file opened at start (a ``dup``: the caller closes it),
        or None once the server is closed."""
        with self._fd_lock:
            return os.dup(self._trace_fd) if self._trace_fd >= 0 else None

    def server_close(self) -> None:
        """Close the listening socket and the trace file (requests in progress keep theirs)."""
        super().server_close()
        with self._fd_lock:
            if self._trace_fd >= 0:
                os.close(self._trace_fd)
                self._trace_fd = -1
