"""Watching a run: real-time pacing, the GUI and its camera, the monitor window, recording, and
traces for the browser viewer (``trace/``).

These wrap the step loop; none is a branch inside it. May import ``devices`` and below;
never ``scenario``.
"""
