"""Watching a run: real-time pacing, the GUI, the monitor window and recording.

These wrap the step loop; none is a branch inside it. May import ``managers`` and below;
never ``scenario``.
"""
