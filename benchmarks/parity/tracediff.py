"""Compare two parity traces and list the differences, path by path."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

ABSENT = "<absent>"
REL_TOL = 1e-6
ABS_TOL = 1e-6


@dataclass
class Difference:
    """One place where the traces disagree."""

    path: str
    incumbent: Any
    ours: Any


def _ok(value: Any) -> str:
    return "ok: " + show(value, 200)


def _same_number(a: float, b: float) -> bool:
    return abs(a - b) <= ABS_TOL + REL_TOL * max(abs(a), abs(b))


def _scalar(value: Any) -> bool:
    return not isinstance(value, (dict, list))


def _error(value: Any) -> str | None:
    return value.get("error") if isinstance(value, dict) else None


def diff(incumbent: Any, ours: Any, path: str = "") -> list[Difference]:
    """Every difference between two plain (JSON) values; numbers compare with a tolerance.

    A dict holding an ``error`` (a probe that raised) is compared as a whole: one line saying
    which side failed and how, instead of one line per key the failed side never recorded.
    """
    if (_error(incumbent) or _error(ours)) and _error(incumbent) != _error(ours):
        return [Difference(path, _error(incumbent) or _ok(incumbent), _error(ours) or _ok(ours))]
    if isinstance(incumbent, bool) or isinstance(ours, bool):
        return [] if incumbent is ours else [Difference(path, incumbent, ours)]
    if isinstance(incumbent, (int, float)) and isinstance(ours, (int, float)):
        return [] if _same_number(incumbent, ours) else [Difference(path, incumbent, ours)]
    if isinstance(incumbent, dict) and isinstance(ours, dict):
        out: list[Difference] = []
        for key in sorted(set(incumbent) | set(ours)):
            sub = f"{path}.{key}" if path else key
            if key not in incumbent:
                out.append(Difference(sub, ABSENT, ours[key]))
            elif key not in ours:
                out.append(Difference(sub, incumbent[key], ABSENT))
            else:
                out += diff(incumbent[key], ours[key], sub)
        return out
    if isinstance(incumbent, list) and isinstance(ours, list):
        return _diff_lists(incumbent, ours, path)
    return [] if incumbent == ours else [Difference(path, incumbent, ours)]


def _diff_lists(inc: list[Any], ours: list[Any], path: str) -> list[Difference]:
    short = len(inc) <= 6 and len(ours) <= 6 and all(map(_scalar, inc + ours))
    if len(inc) == len(ours):
        inner = [
            d
            for i, (a, b) in enumerate(zip(inc, ours, strict=False))
            for d in diff(a, b, f"{path}[{i}]")
        ]
        if not inner or not short:
            return inner if len(inner) <= 8 else [*inner[:8], _more(path, len(inner) - 8)]
        return [Difference(path, inc, ours)]
    if short:
        return [Difference(path, inc, ours)]
    first = next(
        (i for i, (a, b) in enumerate(zip(inc, ours, strict=False)) if diff(a, b)),
        min(len(inc), len(ours)),
    )
    window = slice(max(0, first - 1), first + 2)
    return [
        Difference(f"{path} (len)", len(inc), len(ours)),
        Difference(f"{path}[{window.start}:{window.stop}]", inc[window], ours[window]),
    ]


def _more(path: str, n: int) -> Difference:
    return Difference(f"{path}[...]", f"{n} more differing items", "")


def show(value: Any, width: int = 58) -> str:
    """A value as compact one-line text, cut to ``width`` characters."""
    text = value if isinstance(value, str) else json.dumps(value, separators=(",", ":"))
    return text if len(text) <= width else text[: width - 3] + "..."
