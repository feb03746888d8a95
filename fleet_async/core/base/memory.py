"""Memory: what a spawn may plan to use, and what a run keeps from the garbage collector.

A simulation holds every body in PyBullet and in the state store. Measured on this project's
test machine (Linux, PyBullet 3.2.7), a box ``SimObject`` takes about 20 KiB and a mobile
robot from a URDF about 100 KiB (96 KiB each at 10,000 robots, 131 KiB at 1,000), PyBullet's
body included. A spawn of ``n`` bodies is checked against ``n * BODY_BYTES`` (a lower bound,
so nothing that fits is refused) and ``SimulationParams.memory_share`` of the machine's
physical memory: a grid of ten million robots is a clear error at once, not minutes of
swapping and a MemoryError.

At fleet scale the heap also holds hundreds of thousands of Python objects that live as long
as the simulation: agents, their controllers and plugins, poses, the actions waiting in queues
(435,000 objects at 10,000 realistic robots). A full collection of the garbage collector
(generation 2) walks every one of them, about 120 ms there, and the allocations of busy steps
(plans, goals, missions' events) bring one every 150 steps or so: 1.7 ms a step on average, a
seventh of the step. For the length of a run (``fleet_async.run`` / ``run_async``,
``run_simulation``) :func:`frozen_heap` keeps the objects that exist when it starts out of the
collector's view (``gc.freeze``) and gives them back when it ends (``gc.unfreeze``), so the
run's collections walk only what the run made. What that costs, while the run lasts: cyclic
garbage among the frozen objects (a reference cycle dropped during the run) waits for the first
collection after it, even an explicit ``gc.collect()`` inside the run cannot reclaim it;
``gc.get_objects()`` does not list the frozen objects (a leak hunt sees only what the run
made); and a ``gc.freeze()`` of the program's own made during the run is undone with the run's.
A process that froze objects before the run, or turned the collector off, is left as it is;
``SimulationParams.gc_freeze = False`` turns this off (for a leak hunt, or a run that drops
large cycles of objects it had before).
"""

from __future__ import annotations

import contextlib
import gc
import os
import threading
from collections.abc import Iterator

__all__ = ["BODY_BYTES", "check_spawn_fits", "frozen_heap", "physical_memory"]

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


_lock = threading.Lock()
_runs = 0  # runs in progress that froze the heap (runs may overlap in threads)


@contextlib.contextmanager
def frozen_heap(enabled: bool) -> Iterator[None]:
    """Freeze the objects that exist now for the body of the ``with`` (see the module)."""
    global _runs
    with _lock:
        froze = enabled and gc.isenabled() and (_runs > 0 or gc.get_freeze_count() == 0)
        if froze:
            if _runs == 0:
                gc.freeze()
            _runs += 1
    try:
        yield
    finally:
        if froze:
            with _lock:
                _runs -= 1
                if _runs == 0:
                    gc.unfreeze()
