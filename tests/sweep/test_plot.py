"""The plot of a KPI against a swept key: the series it draws, and the file."""

from __future__ import annotations

import pytest
from PIL import Image

from fleet_async.sweep.plot import plot_kpi, series


def row(i: int, robots: int, policy: str, seed: int) -> dict[str, str]:
    """A table row as read from CSV (text cells), with y = 10 * robots + seed."""
    y = str(robots * 10 + seed)
    return {"run": str(i), "robots": str(robots), "policy": policy, "seed": str(seed), "y": y}


GRID = [(r, p, s) for s in range(4) for p in ("fifo", "nearest") for r in (2, 10, 4)]
ROWS = [{**row(i, *point), "error": ""} for i, point in enumerate(GRID)]
ROWS.append({**row(99, 4, "fifo", 9), "y": "", "error": "boom"})


def test_series_groups_orders_numerically_and_leaves_out_failed_runs():
    lines = series(ROWS, "robots", "y", group_by=["policy"])
    assert list(lines) == [("fifo",), ("nearest",)]
    points = lines[("fifo",)]
    assert [p.x for p in points] == ["2", "4", "10"]  # numbers, not text order
    assert points[0].values == [20.0, 21.0, 22.0, 23.0]
    assert points[0].mean == 21.5 and points[0].percentile(10) == pytest.approx(20.3)
    assert len(points[1].values) == 4  # the failed run is not there


def test_series_names_an_unknown_column():
    with pytest.raises(ValueError, match="--y nope: no such column"):
        series(ROWS, "robots", "nope")


def test_plot_writes_an_image(tmp_path):
    out = plot_kpi(ROWS, "robots", "y", tmp_path / "kpi.png", group_by=["policy"])
    with Image.open(out) as image:
        assert image.format == "PNG" and image.size == (840, 504)
    categorical = plot_kpi(ROWS, "policy", "y", tmp_path / "policy.png", group_by=["robots"])
    assert categorical.exists()


def test_plot_with_nothing_to_draw_says_so(tmp_path):
    with pytest.raises(ValueError, match="no successful run"):
        plot_kpi(ROWS[-1:], "robots", "y", tmp_path / "kpi.png")
