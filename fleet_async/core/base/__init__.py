"""Bottom layer: what every other layer uses.

Enums (``types``), the event bus (``events``), sim-time schedules (``scheduling``), config
mapping and YAML reading (``config_utils``), bounded reprs for error messages (``reprs``), lazy
loggers (``logging_utils``), data-file lookup (``paths``), the one rule for sim seconds to whole
steps (``steps``), and the simulation's settings, which every floor reads (``params``,
``camera_config``). Imports nothing else from ``fleet_async``.
"""
