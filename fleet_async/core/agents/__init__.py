"""``Agent`` (a SimObject under a controller chain with an action queue), its parameters,
plugins, joints API and the fleet's share of the motion phase.

May import ``missions`` and below.
"""
