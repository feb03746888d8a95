"""Async missions on anyio: coroutines that drive the fleet in sim time.

This layer sits on top of ``fleet_async.core`` and compiles missions into the core's action
queues; the core never imports it. (Work in progress: the mission runtime lands with the
async-missions issue.)
"""

__all__: list[str] = []
