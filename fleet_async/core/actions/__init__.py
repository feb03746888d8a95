"""Actions agents run from their queues: move, wait, pick / drop, joint and pose actions.

Actions drive agents, which they know only as a type. May import ``motion`` and below.
"""
