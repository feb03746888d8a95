"""The simulation kernel: the clock, the step loop as named phases, plugins,
profiling.

May import ``agents`` and below.
"""
