"""The mission seam: what the core offers to the async mission layer (``fleet_async.tasks``).

``fleet_async.tasks`` imports the core only through this package. May import ``actions`` and
below.
"""
