"""What a spawn may plan to use: refuse a fleet that cannot fit before building any of it.

A simulation holds every body in PyBullet and in the state store. Measured on this project's
test machine (Linux, PyBullet 3.2.7), a box ``SimObject`` takes about 20 KiB and a mobile
robot from a URDF about 100 KiB (96 KiB each at 10,000 robots, 131 KiB at 1,000), PyBullet's
body included. A spawn of ``n`` bodies is checked against ``n * BODY_BYTES`` (a lower bound,
so nothing that fits is refused) and ``SimulationParams.memory_share`` of the machine's
physical memory: a grid of ten million robots is a clear error at once, not minutes of
swapping and a MemoryError.
"""

from __future__ import annotations

import os

__all__ = ["BODY_BYTES", "check_spawn_fits", "physical_memory"]

BODY_BYTES = 16 * 1024
"""Bytes a body needs at least (the smallest measured, a box object, is about 20 KiB)."""


def physical_memory() -> int | None:
    """This machine's physical memory in bytes, or None where the OS does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, OSError, ValueError):  # not a POSIX system
        return None


def check_spawn_fits(count: int, share: float | None, what: str) -> None:
    """Refuse a spawn of ``count`` bodies that would need more than ``share`` of memory.

    Args:
        count: Bodies the spawn would create.
        share: ``SimulationParams.memory_share`` (None: no simulation to ask, no check).
        what: Where the count comes from, for the message (``file: entities[0].grid``).

    Raises:
        ValueError: naming ``what``, the count, the memory it needs and the machine's.
    """
    total = physical_memory()
    if share is None or total is None or count * BODY_BYTES <= share * total:
        return
    gib = 1024**3
    raise ValueError(
        f"{what}: {count:,} bodies need at least {count * BODY_BYTES / gib:.1f} GiB (16 KiB "
        f"a body at least, about 100 KiB a mobile robot from a URDF), more than "
        f"memory_share={share} of this machine's {total / gib:.1f} GiB; spawn fewer, or raise "
        "SimulationParams.memory_share (the scenario's simulation.memory_share) to allow it"
    )
