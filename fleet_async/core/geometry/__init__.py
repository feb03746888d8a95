"""Poses, paths and the math on them: quaternions, ``Pose``, ``Path``, limits, grids.

Pure numpy (and PyBullet's math helpers); no simulation state. May import ``base``.
"""
