"""How things move: the vectorised kinematic engine, controllers, joints and IK.

Controllers act on agents, which they know only as a type. May import ``bodies`` and below.
"""
