"""Error reporting shared by the scenario loader (``build.py``, ``entities.py``).

Every message starts with the file (``where``) and the section or key (``label``), such as
``scenario.yaml: entities[2].grid: ...``.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from fleet_async.core.base.reprs import short_repr

__all__ = ["config_context", "expect_type", "reject_unknown_keys", "relabel_error", "where_prefix"]


def where_prefix(source: str | os.PathLike[str] | None) -> str:
    return f"{os.fspath(source)}: " if source is not None else ""


def relabel_error(exc: Exception, where: str, label: str) -> Exception:
    """The same kind of error with ``where`` and ``label`` in front (each at most once)."""
    message = str(exc)
    if where and message.startswith(where):
        message = message[len(where) :]
    if not (message.startswith(label) and message[len(label) : len(label) + 1] in (":", ".", "[")):
        message = f"{label}: {message}"
    kind: type[Exception] = ValueError
    for candidate in (FileNotFoundError, TypeError):
        if isinstance(exc, candidate):
            kind = candidate
    return kind(f"{where}{message}")


@contextmanager
def config_context(where: str, label: str, *, resolving: bool = False) -> Iterator[None]:
    """Re-raise configuration errors from the block with the file and section in front.

    With ``resolving`` (the block resolves a dotted path), an import or attribute error is a
    configuration error too.
    """
    caught: tuple[type[Exception], ...] = (ValueError, TypeError, FileNotFoundError)
    try:
        yield
    except caught as exc:
        raise relabel_error(exc, where, label) from exc
    except (ImportError, AttributeError) as exc:
        if not resolving:
            raise
        raise ValueError(f"{where}{label}: {exc}") from exc


def reject_unknown_keys(keys: Sequence[Any], valid: Sequence[str], where: str, label: str) -> None:
    unknown = [key for key in keys if key not in valid]
    if not unknown:
        return
    close = difflib.get_close_matches(str(unknown[0]), list(valid), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise ValueError(
        f"{where}{label}: unknown key {unknown[0]!r}{hint}; valid keys: {', '.join(valid)}"
    )


def expect_type(
    value: Any, kind: type | tuple[type, ...], what: str, where: str, label: str
) -> Any:
    if not isinstance(value, kind):
        raise ValueError(
            f"{where}{label}: expected {what}, got {short_repr(value)} ({type(value).__name__})"
        )
    return value
