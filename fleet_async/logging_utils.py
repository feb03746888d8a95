"""Loggers that build their messages only when they are emitted.

The reference API's ``logging_utils`` module: a thin facade over the modules of the core that
own these names, so a pybullet_fleet script ports by renaming its import
(``pybullet_fleet.logging_utils`` becomes ``fleet_async.logging_utils``). Nothing in fleet_async
imports this module.
"""

from __future__ import annotations

from fleet_async.core.base.logging_utils import (
    LazyLogger,
    NamedLazyLogger,
    get_lazy_logger,
    get_named_lazy_logger,
    lazy_log,
    wrap_existing_logger,
)

__all__ = [
    "LazyLogger",
    "NamedLazyLogger",
    "get_lazy_logger",
    "get_named_lazy_logger",
    "lazy_log",
    "wrap_existing_logger",
]
