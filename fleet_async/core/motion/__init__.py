"""How things move: the vectorised kinematic engine, controllers and building an agent's
controller chain (``chain.py``), joints and IK.

Controllers act on agents, which they know only as a type. May import ``bodies`` and below.
"""
