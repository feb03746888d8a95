"""Managers: groups of objects or agents spawned and driven together, grid spawning, and
the entity-class registry.

May import ``sim`` and below.
"""
