"""GridSpawnParams: a box of grid cells to place spawned objects on.

A grid is a range of integer cell indices per axis, ``x_min..x_max``, ``y_min..y_max`` and
``z_min..z_max`` (inclusive). Cell ``(ix, iy, iz)`` sits at ``offset + (ix, iy, iz) * spacing``
in the world frame (metres). Cells are ordered with X varying fastest, then Y, then Z, and that
order is the order in which the managers fill them.
"""

from __future__ import annotations

import difflib
import math
import numbers
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fleet_async.core.base.config_utils import dataclass_from_dict
from fleet_async.core.base.reprs import short_repr

__all__ = [
    "GridSpawnParams",
    "assign_by_counts",
    "assign_by_probability",
    "assign_first_cells",
]

_COUNT_KEYS = ("count", "spacing", "offset", "columns")


def _is_int(value: Any) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def _vector3(value: Any, field: str) -> list[float]:
    """2 or 3 finite numbers as ``[x, y, z]`` (a missing z is 0), or ValueError naming ``field``."""
    expected = f"GridSpawnParams.{field}: expected 2 or 3 finite numbers, got {short_repr(value)}"
    if isinstance(value, (str, bytes)) or not isinstance(value, (Sequence, np.ndarray)):
        raise ValueError(expected)
    items = list(value)
    if len(items) not in (2, 3) or not all(
        isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) for v in items
    ):
        raise ValueError(expected)
    floats = [float(v) for v in items]
    return floats if len(floats) == 3 else [*floats, 0.0]


@dataclass
class GridSpawnParams:
    """Grid of cells for spawning objects in 3-D space.

    Objects spawn in X -> Y -> Z order. For a 2-D grid leave ``z_min = z_max = 0``; set
    ``z_max > z_min`` for vertical layers.

    Attributes:
        x_min: Minimum X cell index.
        x_max: Maximum X cell index (inclusive, >= ``x_min``).
        y_min: Minimum Y cell index.
        y_max: Maximum Y cell index (inclusive, >= ``y_min``).
        spacing: ``[sx, sy, sz]`` metres between neighbouring cells; ``[sx, sy]`` means
            ``sz = 0``. Each is > 0 on an axis with more than one cell, else >= 0.
        offset: ``[ox, oy, oz]`` world position (metres) of cell ``(0, 0, 0)``; ``[ox, oy]``
            means ``oz = 0``.
        z_min: Minimum Z cell index (default 0).
        z_max: Maximum Z cell index (default 0: one layer).
    """

    x_min: int
    x_max: int
    y_min: int
    y_max: int
    spacing: list[float]
    offset: list[float]
    z_min: int = 0
    z_max: int = 0

    def __post_init__(self) -> None:
        for axis in "xyz":
            lo_name, hi_name = f"{axis}_min", f"{axis}_max"
            lo, hi = getattr(self, lo_name), getattr(self, hi_name)
            for name, value in ((lo_name, lo), (hi_name, hi)):
                if not _is_int(value):
                    raise ValueError(f"GridSpawnParams.{name}: expected an integer, got {value!r}")
            if lo > hi:
                raise ValueError(
                    f"GridSpawnParams.{lo_name}: expected <= {hi_name} ({hi!r}), got {lo!r}"
                )
            setattr(self, lo_name, int(lo))
            setattr(self, hi_name, int(hi))
        self.spacing = _vector3(self.spacing, "spacing")
        self.offset = _vector3(self.offset, "offset")
        self._check_spacing()

    def _check_spacing(self) -> None:
        """Each spacing is >= 0, and > 0 on an axis with more than one cell: a zero spacing
        there stacks objects on one spot, a negative one is a sign error."""
        for i, axis in enumerate("xyz"):
            value = self.spacing[i]
            cells = getattr(self, f"{axis}_max") - getattr(self, f"{axis}_min") + 1
            if value < 0 or (value == 0 and cells > 1):
                expected = "> 0" if cells > 1 else ">= 0"
                raise ValueError(
                    f"GridSpawnParams.spacing: expected the {axis} spacing {expected} (the grid "
                    f"has {cells} cell(s) along {axis}), got {short_repr(self.spacing)}"
                )

    @property
    def total_cells(self) -> int:
        """Total number of grid cells: (x range) * (y range) * (z range)."""
        return (
            (self.x_max - self.x_min + 1)
            * (self.y_max - self.y_min + 1)
            * (self.z_max - self.z_min + 1)
        )

    def cell_positions(self, cells: np.ndarray | None = None) -> np.ndarray:
        """World positions of ``cells`` (indices in X-fastest, then Y, then Z order; every
        cell when None), shape ``(len(cells), 3)``. The work and memory follow the cells
        asked for, not the grid's size."""
        if cells is None:
            cells = np.arange(self.total_cells)
        cells = np.asarray(cells, dtype=np.int64)
        nx = self.x_max - self.x_min + 1
        ny = self.y_max - self.y_min + 1
        index = np.stack(
            [
                cells % nx + self.x_min,
                (cells // nx) % ny + self.y_min,
                cells // (nx * ny) + self.z_min,
            ],
            axis=1,
        ).astype(float)
        return np.asarray(self.offset) + index * np.asarray(self.spacing)

    @classmethod
    def from_count(
        cls,
        count: int,
        columns: int | None = None,
        spacing: Sequence[float] | None = None,
        offset: Sequence[float] | None = None,
    ) -> GridSpawnParams:
        """A one-layer grid with just enough rows for ``count`` objects.

        Args:
            count: Number of objects to place (>= 1).
            columns: Cells per row (X) before wrapping to the next row; default
                ``ceil(sqrt(count))``.
            spacing: ``[sx, sy, sz]`` (or ``[sx, sy]``) metres; default ``[1, 1, 0]``.
            offset: ``[ox, oy, oz]`` (or ``[ox, oy]``) metres; default ``[0, 0, 0]``.

        Returns:
            A grid with ``x_min = y_min = 0``, ``x_max = columns - 1`` and
            ``y_max = ceil(count / columns) - 1``.

        Raises:
            ValueError: for ``count`` or ``columns`` that is not an integer >= 1, or a bad
                ``spacing`` / ``offset``.
        """
        if not _is_int(count) or count < 1:
            raise ValueError(f"GridSpawnParams.count: expected an integer >= 1, got {count!r}")
        count = int(count)
        if columns is None:
            columns = math.isqrt(count - 1) + 1  # ceil(sqrt(count)), exact for integers
        elif not _is_int(columns) or columns < 1:
            raise ValueError(f"GridSpawnParams.columns: expected an integer >= 1, got {columns!r}")
        columns = int(columns)
        rows = -(-count // columns)
        return cls(
            x_min=0,
            x_max=columns - 1,
            y_min=0,
            y_max=rows - 1,
            spacing=_vector3(spacing, "spacing") if spacing is not None else [1.0, 1.0, 0.0],
            offset=_vector3(offset, "offset") if offset is not None else [0.0, 0.0, 0.0],
        )

    @classmethod
    def from_dict(cls, config: Mapping[str, Any], *, source: str | None = None) -> GridSpawnParams:
        """Build from a ``grid:`` config mapping.

        Two formats: explicit ranges (``x_min``, ``x_max``, ``y_min``, ``y_max``, ``spacing``,
        ``offset``, optional ``z_min`` / ``z_max``), or count-based (``count`` with optional
        ``spacing``, ``offset`` and ``columns``, see :meth:`from_count`).

        Raises:
            ValueError: for an unknown key (naming it), a missing key, keys of both formats, or
                a bad value; prefixed with ``source`` when given.
        """
        where = f"{source}: " if source else ""
        if not isinstance(config, Mapping):
            raise ValueError(f"{where}grid: expected a mapping, got {config!r}")
        if "count" not in config:
            return dataclass_from_dict(cls, config, source=source, section="grid")
        unknown = [key for key in config if key not in _COUNT_KEYS]
        if unknown:
            close = difflib.get_close_matches(str(unknown[0]), _COUNT_KEYS, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ValueError(
                f"{where}grid: unknown key(s) {unknown} with 'count'{hint}; "
                f"valid keys for a count-based grid: {list(_COUNT_KEYS)}"
            )
        try:
            return cls.from_count(
                config["count"], config.get("columns"), config.get("spacing"), config.get("offset")
            )
        except ValueError as exc:
            raise ValueError(f"{where}grid: {exc}") from exc


# ----- which object goes to which cell ----------------------------------------------------
# Each function returns (cells, kinds): spawn an object of type kinds[k] at cell cells[k],
# cells increasing, so objects are created in cell order whatever the draw was.


def _count(value: Any, what: str) -> int:
    if not _is_int(value) or value < 0:
        raise ValueError(f"{what}: expected an integer >= 0, got {value!r}")
    return int(value)


def _check_fits(count: int, grid: GridSpawnParams, what: str) -> None:
    if not isinstance(grid, GridSpawnParams):
        raise TypeError(f"{what}: expected GridSpawnParams, got {grid!r}")
    if count > grid.total_cells:
        raise ValueError(
            f"{what}: {count} objects do not fit the grid's total_cells={grid.total_cells}"
        )


def assign_first_cells(
    grid: GridSpawnParams, count: int, what: str = "spawn_objects_grid"
) -> tuple[np.ndarray, np.ndarray]:
    """One type on the first ``count`` cells.

    Raises:
        ValueError: for a negative ``count`` or more than ``grid.total_cells``.
    """
    n = _count(count, f"{what}.num_objects")
    _check_fits(n, grid, what)
    return np.arange(n), np.zeros(n, dtype=int)


def assign_by_probability(
    grid: GridSpawnParams,
    count: int,
    probabilities: Sequence[float],
    rng: Callable[[], np.random.Generator],
    what: str = "spawn_grid_mixed",
) -> tuple[np.ndarray, np.ndarray]:
    """Draw a type for each of the first ``count`` cells.

    One uniform draw per cell picks type ``i`` with probability ``probabilities[i]``; a draw
    past their sum leaves the cell empty. ``rng`` gives the generator, asked for only once the
    arguments are known to be good (so their errors come first).

    Raises:
        ValueError: for a probability outside [0, 1], a sum > 1, or too many cells.
    """
    n = _count(count, f"{what}.num_objects")
    _check_fits(n, grid, what)
    probs = list(probabilities)
    for i, prob in enumerate(probs):
        real = isinstance(prob, numbers.Real) and not isinstance(prob, bool)
        if not (real and 0.0 <= prob <= 1.0):
            raise ValueError(f"{what}: probability of entry {i} must be in [0, 1], got {prob!r}")
    if math.fsum(probs) > 1.0 + 1e-9:
        raise ValueError(f"{what}: probabilities must sum to <= 1, got {probs} (sum {sum(probs)})")
    kinds = np.searchsorted(np.cumsum(probs), rng().random(n), side="right")
    cells = np.flatnonzero(kinds < len(probs))
    return cells, kinds[cells]


def assign_by_counts(
    grid: GridSpawnParams,
    counts: Sequence[int],
    rng: Callable[[], np.random.Generator],
    what: str = "spawn_grid_counts",
) -> tuple[np.ndarray, np.ndarray]:
    """Exactly ``counts[i]`` cells of type ``i``, spread over the grid by a shuffle (``rng``
    gives the generator, asked for once the counts are known to fit).

    Raises:
        ValueError: for a negative count or a total above ``grid.total_cells``.
    """
    n = [_count(c, f"{what}: count of entry {i}") for i, c in enumerate(counts)]
    _check_fits(sum(n), grid, what)
    labels = np.full(grid.total_cells, -1)
    labels[: sum(n)] = np.repeat(np.arange(len(n)), n)
    labels = rng().permutation(labels)
    cells = np.flatnonzero(labels >= 0)
    return cells, labels[cells]
