"""A sweep's results on disk: rows appended as runs finish, resumable, sorted when done.

CSV (the default) is its own journal: each finished run's row is appended and flushed at once,
so an interrupted sweep loses nothing it finished, and a restarted one reads the rows back and
skips their runs. When the sweep ends (or stops) the file is rewritten sorted by run number,
which makes it independent of the order runs finished in.

Parquet (``.parquet``, needs pyarrow) cannot be appended to: rows go to a JSON-lines journal
beside it (``<out>.partial.jsonl``), and the Parquet file is written from the journal and the
rows it already held when the sweep ends; then the journal is removed.

A table written by a different sweep (other columns, or another grid point or seed for a run
number) is refused rather than mixed with.
"""

from __future__ import annotations

import csv
import decimal
import json
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "PARQUET_MISSING",
    "SIM_TIME_COLUMNS",
    "ResultTable",
    "cell_text",
    "read_table",
    "round_sim_times",
]

PARQUET_MISSING = (
    "writing Parquet needs pyarrow, which is not installed: pip install pyarrow "
    "(or write CSV: --out results.csv)"
)


SIM_TIME_COLUMNS = frozenset(
    {
        "sim_time_s",
        "moving_time_total_s",
        "waiting_time_total_s",
        "idle_time_total_s",
        "moving_time_s",
        "waiting_time_s",
        "idle_time_s",
    }
)
"""Columns that hold a whole number of steps times the timestep (sim seconds)."""


def _decimals(timestep: float) -> int:
    """Decimal places of ``timestep`` as written (0.1 -> 1, 0.025 -> 3; at most 12)."""
    exponent = decimal.Decimal(repr(float(timestep))).normalize().as_tuple().exponent
    return min(12, max(0, -exponent)) if isinstance(exponent, int) else 12


def round_sim_times(row: Mapping[str, Any], timestep: float) -> dict[str, Any]:
    """``row`` with its sim-time columns (:data:`SIM_TIME_COLUMNS`) rounded to the timestep's
    decimal places: a count of steps times 0.1 s reads ``23.4``, not ``23.400000000000002``.
    Means (``..._mean_s``) are left as computed."""
    places = _decimals(timestep)
    return {
        key: round(value, places) if key in SIM_TIME_COLUMNS and isinstance(value, float) else value
        for key, value in row.items()
    }


def cell_text(value: Any) -> str:
    """How a value reads in CSV: ``""`` for None, ``str`` otherwise (floats round-trip)."""
    return "" if value is None else str(value)


def _import_parquet() -> Any:
    try:
        import pyarrow.parquet as pq
    except ImportError as exc:
        raise ImportError(PARQUET_MISSING) from exc
    return pq


def _read_csv(path: Path) -> tuple[list[str] | None, list[dict[str, Any]]]:
    """(header, rows) of a CSV table; a last line cut short by a crash is dropped."""
    text = path.read_text(encoding="utf-8")
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]  # the unfinished row of an interrupted write
    lines = list(csv.reader(text.splitlines()))
    if not lines:
        return None, []
    header = lines[0]
    rows = [dict(zip(header, line, strict=True)) for line in lines[1:] if len(line) == len(header)]
    return header, rows


def _read_parquet(path: Path) -> tuple[list[str], list[dict[str, Any]]]:
    table = _import_parquet().read_table(path)
    return list(table.column_names), table.to_pylist()


def _read_journal(path: Path) -> list[dict[str, Any]]:
    rows = []
    for line in path.read_text(encoding="utf-8").splitlines(keepends=True):
        if line.endswith("\n") and line.strip():
            rows.append(json.loads(line))
    return rows


def read_table(path: str | Path) -> list[dict[str, Any]]:
    """The rows of a finished CSV or Parquet table (CSV cells as text)."""
    path = Path(path)
    if path.suffix == ".parquet":
        return _read_parquet(path)[1]
    return _read_csv(path)[1]


class ResultTable:
    """One table of a sweep (the run summaries, or the per-robot detail).

    Args:
        path: The file (``.parquet`` for Parquet, anything else CSV).
        columns: The columns, in order; the first is the run number.
        key_columns: Columns that identify a run (run number, swept values, seed), checked
            against ``expected`` when an existing table is resumed.
        expected: ``run number -> {key column: value}`` of the sweep being run.
        only_runs: Keep the rows of these runs only (the per-robot rows of a run whose
            summary row was never written are dropped: the run is done again).

    Raises:
        ValueError: if the file holds a table of another sweep.
        ImportError: for Parquet without pyarrow.
    """

    def __init__(
        self,
        path: str | Path,
        columns: Sequence[str],
        key_columns: Sequence[str],
        expected: Mapping[int, Mapping[str, Any]],
        only_runs: set[int] | None = None,
    ) -> None:
        self.path = Path(path)
        self.columns = list(columns)
        self.parquet = self.path.suffix == ".parquet"
        self.journal = self.path.with_name(self.path.name + ".partial.jsonl")
        if self.parquet:
            _import_parquet()
        self.rows = self._load()
        self._check(key_columns, expected)
        if only_runs is not None:
            self.rows = [row for row in self.rows if int(row["run"]) in only_runs]
        if self.parquet and self.journal.exists():
            self._rewrite(self.rows)  # one file again: what an earlier sweep left in its journal
        self._stream = self._open_for_append()

    @property
    def runs(self) -> set[int]:
        """Run numbers that have rows."""
        return {int(row["run"]) for row in self.rows}

    # ----- reading what is there ------------------------------------------------------------

    def _load(self) -> list[dict[str, Any]]:
        rows: list[dict[str, Any]] = []
        if self.parquet:
            if self.path.exists():
                columns, rows = _read_parquet(self.path)
                self._check_header(columns, self.path)
            if self.journal.exists():
                rows += _read_journal(self.journal)
        elif self.path.exists():
            header, rows = _read_csv(self.path)
            if header is not None:
                self._check_header(header, self.path)
        return rows

    def _check_header(self, header: list[str], where: Path) -> None:
        if header != self.columns:
            raise ValueError(
                f"{where} holds a table of another sweep (its columns: {', '.join(header)}; "
                f"this sweep's: {', '.join(self.columns)}); write to another file with --out, "
                "or remove it"
            )

    def _check(self, key_columns: Sequence[str], expected: Mapping[int, Mapping[str, Any]]) -> None:
        for row in self.rows:
            run = int(row["run"])
            want = expected.get(run)
            if want is None:
                raise ValueError(
                    f"{self.path} has a row for run {run}, which this sweep does not have "
                    f"(it has runs 0..{len(expected) - 1}); write to another file with --out, "
                    "or remove it"
                )
            for column in key_columns:
                if cell_text(row.get(column)) != cell_text(want[column]):
                    raise ValueError(
                        f"{self.path}: run {run} has {column}={cell_text(row.get(column))!r} "
                        f"there, but this sweep's run {run} has "
                        f"{column}={cell_text(want[column])!r}: the file holds another sweep; "
                        "write to another file with --out, or remove it"
                    )

    # ----- writing ----------------------------------------------------------------------------

    def _open_for_append(self) -> Any:
        if self.parquet:
            return self.journal.open("a", encoding="utf-8")
        fresh = not self.path.exists() or self.path.stat().st_size == 0
        if not fresh:
            self._rewrite(self.rows)  # drops a row cut short by a crash
        stream = self.path.open("a", encoding="utf-8", newline="")
        if fresh:
            csv.writer(stream).writerow(self.columns)
            stream.flush()
        return stream

    def append(self, rows: Iterable[Mapping[str, Any]]) -> None:
        """Write rows at once (flushed: an interrupted sweep keeps them)."""
        new = [{c: row.get(c) for c in self.columns} for row in rows]
        if not new:
            return
        if self.parquet:
            for row in new:
                self._stream.write(json.dumps(row) + "\n")
        else:
            writer = csv.writer(self._stream)
            for row in new:
                writer.writerow([cell_text(row[c]) for c in self.columns])
        self._stream.flush()
        self.rows.extend(new)

    def finish(self, sort_key: Callable[[dict[str, Any]], Any] | None = None) -> None:
        """Close the file and rewrite it sorted by run number (stable: rows of one run keep
        their order); for Parquet, write the file and remove the journal."""
        self._stream.close()
        self.rows.sort(key=sort_key or (lambda row: int(row["run"])))
        self._rewrite(self.rows)

    def _rewrite(self, rows: list[dict[str, Any]]) -> None:
        tmp = self.path.with_name(self.path.name + ".tmp")
        if self.parquet:
            import pyarrow as pa

            if rows:
                table = pa.Table.from_pylist(
                    [{c: row.get(c) for c in self.columns} for row in rows]
                )
            else:
                table = pa.table({c: pa.array([], pa.null()) for c in self.columns})
            _import_parquet().write_table(table, tmp)
            os.replace(tmp, self.path)
            if self.journal.exists():  # every row is in the Parquet file now
                self.journal.unlink()
            return
        else:
            with tmp.open("w", encoding="utf-8", newline="") as stream:
                writer = csv.writer(stream)
                writer.writerow(self.columns)
                for row in rows:
                    writer.writerow([cell_text(row.get(c)) for c in self.columns])
        os.replace(tmp, self.path)
