"""The browser replay viewer for traces, and a Python reader for trace files.

``fleet-async view RUN.fatrace`` serves the viewer page (``static/``, shipped in the package,
no build step) and the trace on a local port; :class:`TraceReader` reads a trace into numpy
arrays. Traces are written by ``sim.start_trace`` (``fleet_async.core.view.trace``).
"""

from fleet_async.viewer.reader import (
    Frame,
    TraceCutWarning,
    TraceFormatError,
    TraceReader,
    check_trace,
)

__all__ = ["Frame", "TraceCutWarning", "TraceFormatError", "TraceReader", "check_trace"]
