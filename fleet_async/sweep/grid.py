"""The runs of a sweep: seeds, a parameter grid, and the deterministic order of their product.

A sweep runs every point of the grid (the product of each swept key's values, the last key
varying fastest) with every seed. Runs are numbered **seed-major**: run ``i`` has seed
``seeds[i // points]`` and grid point ``i % points``. So adding seeds to a sweep (``0:100`` ->
``0:200``) keeps every run number it had, and a resumed sweep can extend a table; and the
first runs cover the whole grid once before any point gets a second seed.
"""

from __future__ import annotations

import dataclasses
import itertools
import re
from collections.abc import Mapping, Sequence
from typing import Any

import yaml

from fleet_async.core.base.yaml_scalars import load_yaml_text

__all__ = ["SweepPlan", "parse_assignment", "parse_seeds", "parse_value"]

_INT = re.compile(r"[+-]?\d+")


@dataclasses.dataclass(frozen=True)
class SweepPlan:
    """Every run of a sweep, in run-number order.

    Args:
        grid: ``{key: [values]}``, in the order the keys were given (the last varies fastest).
        seeds: The seeds, in order.

    Raises:
        ValueError: for no seeds, a key without values, or a seed that is not an integer.
    """

    grid: Mapping[str, Sequence[Any]]
    seeds: Sequence[int]

    def __post_init__(self) -> None:
        if not self.seeds:
            raise ValueError("a sweep needs at least one seed")
        for seed in self.seeds:
            if isinstance(seed, bool) or not isinstance(seed, int):
                raise ValueError(f"seeds: expected integers, got {seed!r}")
        for key, values in self.grid.items():
            if not values:
                raise ValueError(f"--set {key}: no values")

    @property
    def keys(self) -> list[str]:
        """The swept keys, in order."""
        return list(self.grid)

    @property
    def points(self) -> list[dict[str, Any]]:
        """The grid points, ``{key: value}`` each (one empty point without a grid)."""
        keys = self.keys
        return [
            dict(zip(keys, combo, strict=True)) for combo in itertools.product(*self.grid.values())
        ]

    def __len__(self) -> int:
        count = len(self.seeds)
        for values in self.grid.values():
            count *= len(values)
        return count

    def run(self, index: int) -> tuple[dict[str, Any], int]:
        """(grid point, seed) of run ``index``."""
        points = self.points
        return points[index % len(points)], self.seeds[index // len(points)]

    def runs(self) -> list[tuple[int, dict[str, Any], int]]:
        """Every run as (run number, grid point, seed), in run-number order."""
        points = self.points
        return [
            (s * len(points) + p, dict(point), seed)
            for s, seed in enumerate(self.seeds)
            for p, point in enumerate(points)
        ]


def parse_seeds(text: str) -> list[int]:
    """Seeds from ``START:STOP[:STEP]`` (STOP excluded, as ``range``), ``N`` or ``A,B,C``.

    Raises:
        ValueError: naming the text, for anything else or an empty range.
    """
    text = text.strip()
    try:
        if ":" in text:
            parts = [int(p) for p in text.split(":")]
            if len(parts) not in (2, 3):
                raise ValueError
            seeds = list(range(*parts))
        else:
            seeds = [int(p) for p in text.split(",")]
    except ValueError:
        raise ValueError(
            f"--seeds {text!r}: expected START:STOP (e.g. 0:100, STOP excluded), "
            "START:STOP:STEP, one integer, or a comma-separated list"
        ) from None
    if not seeds:
        raise ValueError(f"--seeds {text!r}: the range is empty")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"--seeds {text!r}: a seed is given twice")
    return seeds


def parse_value(text: str) -> Any:
    """One value of ``--set``, read by the same scalar rule as scenario files
    (``fleet_async.core.base.yaml_scalars``): a number, true/false/null, a YAML flow list or
    mapping (``[0, 0, 0.1]``), or else the text itself.

    Raises:
        ValueError: for a form the rule refuses (``no``, ``1:30``, ``0x1F``), naming it.
    """
    text = text.strip()
    try:
        value = load_yaml_text(text)
    except yaml.constructor.ConstructorError as exc:
        raise ValueError(f"--set value {text!r}: {exc.problem}") from exc
    except yaml.YAMLError:
        return text
    return text if value is None and text not in ("null", "~") else value


def _split_top_level(text: str) -> list[str]:
    """Split at commas that are not inside brackets or braces."""
    parts: list[str] = []
    current: list[str] = []
    depth = 0
    for char in text:
        if char in "[{":
            depth += 1
        elif char in "]}":
            depth -= 1
        if char == "," and depth == 0:
            parts.append("".join(current))
            current = []
        else:
            current.append(char)
    parts.append("".join(current))
    return parts


def parse_assignment(text: str) -> tuple[str, list[Any]]:
    """``KEY=V1,V2,...`` -> (KEY, [values]); commas inside ``[...]`` or ``{...}`` do not split.

    Raises:
        ValueError: without ``=``, with an empty key or value, or a value given twice.
    """
    key, sep, values_text = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ValueError(f"--set {text!r}: expected KEY=VALUE[,VALUE...]")
    parts = _split_top_level(values_text)
    if any(not p.strip() for p in parts):
        raise ValueError(f"--set {text!r}: an empty value (two commas in a row, or none after =)")
    values = [parse_value(p) for p in parts]
    rendered = [repr(v) for v in values]
    if len(set(rendered)) != len(rendered):
        raise ValueError(f"--set {text!r}: a value is given twice")
    return key, values
