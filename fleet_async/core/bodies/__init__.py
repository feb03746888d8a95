"""``SimObject`` (a handle onto one row of the state store), its spawn parameters, body
creation (one by one or in batches) and the robot model registry.

May import ``collision``, ``world``, ``geometry`` and ``base``.
"""
