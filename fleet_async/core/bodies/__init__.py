"""``SimObject`` (a handle onto one row of the state store), its spawn parameters, body
creation (one by one, in batches or from an SDF file) and the robot model registry.

May import ``collision``, ``world``, ``geometry`` and ``base``.
"""
