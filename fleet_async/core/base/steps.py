"""Sim seconds to whole steps: the one rounding rule of the package.

``sim_time = step_count * timestep``, so a duration or a sim time given in seconds becomes a
step count here, and only here: the mission runtime (sleeps, timeouts, deadlines,
``run(until=)``), the command line and the sweeps all round the same way.
"""

from __future__ import annotations

import math

__all__ = ["STEP_EPS", "steps_for"]

STEP_EPS = 1e-9
"""Tolerance (in steps) that absorbs float error such as 0.3 / 0.1 = 2.9999999999999996."""


def steps_for(seconds: float, timestep: float) -> int:
    """The fewest whole steps of ``timestep`` covering ``seconds`` (both in sim seconds).

    Also the step at which sim time ``seconds`` is reached, counting from step 0. Negative
    ``seconds`` give a step count <= 0; callers that need a count clamp it.
    """
    return math.ceil(seconds / timestep - STEP_EPS)
