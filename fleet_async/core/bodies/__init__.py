"""``SimObject`` (a handle onto one row of the state store), its constructors
(``constructors.py``) and spawn parameters, body creation (one by one, deferred and batched, or
from an SDF file) and the robot model registry.

May import ``collision``, ``world``, ``geometry`` and ``base``.
"""
