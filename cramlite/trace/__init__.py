"""Traces of executed motion (`cramlite-trace/1`, JSON Lines): writing, reading, replay."""

from cramlite.trace.format import TRACE_FORMAT, Trace, TraceError, TraceWriter, read_trace

__all__ = ["TRACE_FORMAT", "Trace", "TraceError", "TraceWriter", "read_trace"]
