"""Poses, paths and the math on them: quaternions, ``Pose``, ``Path``, kinematic limits,
vectors and frames, grids, approach poses, poses read from config.

numpy (and PyBullet's math helpers) only; no simulation state. May import ``base``.
"""
