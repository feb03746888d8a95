"""A KPI against a swept parameter, with its spread over seeds (needs matplotlib).

For each value of the parameter on the x axis, the seeds' values of the KPI are drawn as faint
dots, their mean as a line, and the band between their 10th and 90th percentiles. When the
sweep has other keys, each combination of their values gets a line of its own. Failed runs
(rows with an error) are left out, and the title says how many.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fleet_async.sweep.table import cell_text

__all__ = ["PLOT_MISSING", "SeriesPoint", "plot_kpi", "require_matplotlib", "series"]

PLOT_MISSING = "--plot needs matplotlib, which is not installed: python -m pip install -e '.[plot]'"


def require_matplotlib() -> Any:
    """``matplotlib.pyplot`` on the file-only Agg backend.

    Raises:
        ImportError: naming the ``plot`` extra, when matplotlib is missing.
    """
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only: never a window
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise ImportError(PLOT_MISSING) from exc
    return plt


def _number(value: Any) -> float | None:
    """A cell as a float (tables read from CSV hold text), or None."""
    if value is None or value == "" or isinstance(value, bool):
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


class SeriesPoint:
    """The seeds' values of the KPI at one x value of one line."""

    __slots__ = ("values", "x")

    def __init__(self, x: Any) -> None:
        self.x = x
        self.values: list[float] = []

    @property
    def mean(self) -> float:
        """Mean over seeds."""
        return float(np.mean(self.values))

    def percentile(self, q: float) -> float:
        """The ``q``-th percentile over seeds."""
        return float(np.percentile(self.values, q))


def series(
    rows: Sequence[Mapping[str, Any]], x: str, y: str, group_by: Sequence[str] = ()
) -> dict[tuple[str, ...], list[SeriesPoint]]:
    """``{group values: [points in x order]}`` from the table's rows (failed rows left out).

    Raises:
        ValueError: if ``x`` or ``y`` is not a column of the table.
    """
    columns = set(rows[0]) if rows else set()
    for name, what in ((x, "--x"), (y, "--y")):
        if rows and name not in columns:
            raise ValueError(f"{what} {name}: no such column; the table has {', '.join(rows[0])}")
    lines: dict[tuple[str, ...], dict[str, SeriesPoint]] = {}
    for row in rows:
        if row.get("error") not in (None, ""):
            continue
        value = _number(row.get(y))
        if value is None:
            continue
        # Keys by text: swept values may be lists, and CSV cells are text anyway.
        group = tuple(cell_text(row.get(g)) for g in group_by)
        points = lines.setdefault(group, {})
        key = row.get(x)
        points.setdefault(cell_text(key), SeriesPoint(key)).values.append(value)

    def order(point: SeriesPoint) -> tuple[int, float, str]:
        number = _number(point.x)
        return (0, number, "") if number is not None else (1, 0.0, str(point.x))

    return {group: sorted(points.values(), key=order) for group, points in lines.items()}


def plot_kpi(
    rows: Sequence[Mapping[str, Any]],
    x: str,
    y: str,
    out: str | Path,
    group_by: Sequence[str] = (),
    title: str | None = None,
) -> Path:
    """Draw ``y`` against ``x`` over seeds into ``out`` (PNG, SVG or PDF by its suffix).

    Args:
        rows: The sweep's table (as ``run_sweep`` returns it or ``read_table`` reads it).
        x: The swept key on the x axis.
        y: The KPI column.
        out: The image file.
        group_by: Other swept keys: one line per combination of their values.
        title: Defaults to "<y> vs <x>" with the number of seeds.

    Returns:
        ``out`` as a Path.

    Raises:
        ImportError: naming the ``plot`` extra, when matplotlib is missing.
        ValueError: for an unknown column, or no successful run to draw.
    """
    plt = require_matplotlib()
    lines = series(rows, x, y, group_by)
    if not lines:
        raise ValueError(f"--plot: no successful run has a value of {y!r} to draw")
    numeric = all(_number(p.x) is not None for points in lines.values() for p in points)
    labels = sorted({cell_text(p.x) for points in lines.values() for p in points})

    def position(point: SeriesPoint) -> float:
        number = _number(point.x)
        return number if numeric and number is not None else float(labels.index(cell_text(point.x)))

    fig, ax = plt.subplots(figsize=(7.0, 4.2), dpi=120)
    for i, (group, points) in enumerate(sorted(lines.items(), key=lambda kv: str(kv[0]))):
        color = f"C{i % 10}"
        xs = [position(p) for p in points]
        for px, point in zip(xs, points, strict=True):
            ax.scatter([px] * len(point.values), point.values, s=9, color=color, alpha=0.25, lw=0)
        ax.fill_between(
            xs,
            [p.percentile(10) for p in points],
            [p.percentile(90) for p in points],
            color=color,
            alpha=0.15,
            lw=0,
        )
        name = ", ".join(f"{g}={v}" for g, v in zip(group_by, group, strict=True)) or "mean"
        ax.plot(xs, [p.mean for p in points], "o-", color=color, lw=1.8, ms=4, label=name)
    if not numeric:
        ax.set_xticks(range(len(labels)), labels)
    seeds = max(len(p.values) for points in lines.values() for p in points)
    failed = sum(row.get("error") not in (None, "") for row in rows)
    note = f", {failed} failed runs left out" if failed else ""
    detail = f"mean, 10-90% band and every run; {seeds} seeds per point{note}"
    ax.set_title(title or f"{y} vs {x}\n{detail}", fontsize=10)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    out = Path(out)
    fig.savefig(out)
    plt.close(fig)
    return out
