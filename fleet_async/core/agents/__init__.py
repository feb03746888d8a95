"""``Agent``: a SimObject under a controller chain (``agent_motion.py``) with an action queue,
joints and IK (``agent_joints.py``), plugins (``agent_plugins.py``) and spawn parameters
(``agent_params.py``); and ``FleetMotion`` (``fleet.py``), the agents' share of the motion phase.

May import ``missions`` and below.
"""
