"""OccupancyGrid: a map's occupied cells, and their merge into few rectangles.

Row 0 of ``occupied`` is the map's *bottom* row (smallest y), column 0 its left column
(smallest x): cell (row, col) covers ``x in [ox + col * r, ox + (col + 1) * r]`` and
``y in [oy + row * r, oy + (row + 1) * r]`` for resolution ``r`` and origin ``(ox, oy)`` (the
map's yaw is not supported: 0 only). Image formats store the top row first; the readers flip.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["OccupancyGrid"]


@dataclass
class OccupancyGrid:
    """Occupied cells on a regular grid.

    Attributes:
        occupied: (rows, cols) bool, row 0 at the bottom (see the module doc).
        resolution: Cell edge (m, > 0).
        origin: World (x, y) of the bottom-left corner of cell (0, 0) (m).
    """

    occupied: np.ndarray
    resolution: float = 1.0
    origin: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        self.occupied = np.asarray(self.occupied, dtype=bool)
        if self.occupied.ndim != 2:
            raise ValueError(
                f"OccupancyGrid.occupied: expected a 2-D array, got shape {self.occupied.shape}"
            )
        if not (isinstance(self.resolution, (int, float)) and self.resolution > 0):
            raise ValueError(
                f"OccupancyGrid.resolution: expected a number > 0 (m), got {self.resolution!r}"
            )
        self.resolution = float(self.resolution)
        self.origin = (float(self.origin[0]), float(self.origin[1]))

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        rows, cols = self.occupied.shape
        return int(rows), int(cols)

    def cell_center(self, row: int, col: int) -> tuple[float, float]:
        """World (x, y) (m) of the centre of cell (row, col)."""
        r = self.resolution
        return self.origin[0] + (col + 0.5) * r, self.origin[1] + (row + 0.5) * r

    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell holding world point (x, y) (may lie outside the grid)."""
        r = self.resolution
        return int(np.floor((y - self.origin[1]) / r)), int(np.floor((x - self.origin[0]) / r))

    def is_free(self, row: int, col: int) -> bool:
        """Whether (row, col) is inside the grid and not occupied."""
        rows, cols = self.shape
        return 0 <= row < rows and 0 <= col < cols and not bool(self.occupied[row, col])

    def rectangles(self) -> np.ndarray:
        """The occupied cells as few axis-aligned rectangles, (K, 4) ints
        ``(row0, col0, row1, col1)``, end-exclusive, covering every occupied cell once.

        Greedy: each row's runs of occupied cells, then runs with the same columns in
        consecutive rows merge into one rectangle. A warehouse's shelf rows become a
        rectangle each; a maze's walls a few per wall.
        """
        occ = self.occupied
        rows = occ.shape[0]
        padded = np.zeros((rows, occ.shape[1] + 2), dtype=np.int8)
        padded[:, 1:-1] = occ
        change = np.diff(padded, axis=1)
        open_runs: dict[tuple[int, int], int] = {}  # (col0, col1) -> first row
        out: list[tuple[int, int, int, int]] = []
        for row in range(rows + 1):
            if row < rows:
                starts = np.flatnonzero(change[row] == 1)
                ends = np.flatnonzero(change[row] == -1)
                runs = set(zip(starts.tolist(), ends.tolist(), strict=True))
            else:
                runs = set()
            for run in [r for r in open_runs if r not in runs]:
                out.append((open_runs.pop(run), run[0], row, run[1]))
            for run in runs:
                open_runs.setdefault(run, row)
        out.sort()
        return np.array(out, dtype=np.int64).reshape(-1, 4)

    def boxes(self, z0: float, z1: float) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) (K, 3) world corners of :meth:`rectangles`, from ``z0`` to ``z1`` (m)."""
        rect = self.rectangles().astype(float)
        r, (ox, oy) = self.resolution, self.origin
        lo = np.column_stack((ox + rect[:, 1] * r, oy + rect[:, 0] * r, np.full(len(rect), z0)))
        hi = np.column_stack((ox + rect[:, 3] * r, oy + rect[:, 2] * r, np.full(len(rect), z1)))
        return lo, hi
