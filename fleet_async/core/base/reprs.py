"""short_repr: a bounded ``repr`` for the values error messages show.

A value that reaches an error message may be huge (a long list, a YAML alias expanded a million
times): the message shows its start, cut at a bounded number of items per container, levels
and characters, so building the message costs little whatever the value's size.
"""

from __future__ import annotations

import reprlib
from typing import Any

__all__ = ["REPR_LIMIT", "short_repr"]

REPR_LIMIT = 200
"""Characters of a value an error message shows at most (before the ``...``)."""

_REPR = reprlib.Repr()
_REPR.maxlevel = 4
_REPR.maxtuple = _REPR.maxlist = _REPR.maxarray = 12
_REPR.maxdict = _REPR.maxset = _REPR.maxfrozenset = _REPR.maxdeque = 12
_REPR.maxstring = _REPR.maxother = _REPR.maxlong = REPR_LIMIT


def short_repr(value: Any, limit: int = REPR_LIMIT) -> str:
    """``repr(value)`` cut to about ``limit`` characters, ``...`` marking each cut.

    Containers show their first 12 items and 4 levels, so the work is bounded even for a
    value whose full ``repr`` would be gigabytes.

    Args:
        value: Any object.
        limit: Characters kept at most, plus a trailing ``...`` when cut (>= 1).
    """
    text = _REPR.repr(value)
    return text if len(text) <= limit else text[:limit] + "..."
