"""Collision detection on the state store: per-row geometry and world AABBs (``geometry.py``),
the broad phase (``broadphase.py``), the narrow phase and the swept test (``narrowphase.py``),
active pairs (``pairs.py``), the check and its events (``system.py``), and the simulation's
collision methods (``api.py``, mixed into the kernel).

May import ``world``, ``geometry`` and ``base``.
"""
