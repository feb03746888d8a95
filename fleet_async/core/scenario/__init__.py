"""Building a simulation from a scenario mapping or YAML file, and loading worlds (Gazebo
``.world``, SDF, mesh directories).

May import ``managers`` and below; never ``view``.
"""
