"""Traces: a run recorded for the browser viewer (``fleet-async view``), one file per run.

``sim.start_trace("run.fatrace")`` (:class:`TraceApi`, mixed into the simulation) starts a
:class:`TraceWriter` (``writer.py``), which watches the run from outside its step loop. The
format (``format.py``) is specified in ``docs/trace-format.md``;
``fleet_async.viewer.TraceReader`` reads a trace back into numpy arrays.
"""

from fleet_async.core.view.trace.api import TraceApi
from fleet_async.core.view.trace.writer import TraceWriter

__all__ = ["TraceApi", "TraceWriter"]
