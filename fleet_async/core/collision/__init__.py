"""Collision detection on the state store: broad phase, narrow phase, active pairs and their
events (``system.py``), and the simulation's collision methods (``api.py``, mixed into the
kernel).

May import ``world``, ``geometry`` and ``base``.
"""
