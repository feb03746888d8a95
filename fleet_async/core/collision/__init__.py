"""Collision detection on the state store: broad phase, narrow phase, active pairs.

May import ``world``, ``geometry`` and ``base``.
"""
