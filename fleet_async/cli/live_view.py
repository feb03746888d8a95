"""``fleet-async run ... --view``: the viewer page following the run's trace as it is written."""

from __future__ import annotations

import threading

from fleet_async.cli.errors import CliError
from fleet_async.cli.view import open_viewer, warn
from fleet_async.core import MultiRobotSimulationCore
from fleet_async.viewer.server import ViewerServer

__all__ = ["serve_until_interrupted", "start"]


def start(sim: MultiRobotSimulationCore, port: int) -> tuple[ViewerServer, threading.Thread]:
    """Serve the running trace of ``sim`` (live) from a background thread; print the address."""
    tracer = sim.tracer
    assert tracer is not None  # the run command starts the trace first
    try:
        server = ViewerServer(tracer.path, port=port, follow=True, notice=warn)
    except OSError as exc:
        raise CliError(
            f"--view: cannot listen on port {port} ({exc.strerror}); pick another with --view-port"
        ) from exc
    thread = server.start_background()
    open_viewer(server, no_browser=False)
    return server, thread


def serve_until_interrupted(live: tuple[ViewerServer, threading.Thread], keep: bool) -> None:
    """After the run: keep the page served until Ctrl+C (``keep``), then stop the server."""
    server, thread = live
    try:
        if keep:
            print(f"the run is over; the viewer stays at {server.url} until Ctrl+C", flush=True)
            thread.join()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
