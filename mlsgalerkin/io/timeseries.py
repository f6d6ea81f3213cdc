"""Scalar time series (energies, forces, probes) as a CSV file rewritten atomically.

:class:`TimeSeriesWriter` keeps the rows in memory and :meth:`~TimeSeriesWriter.flush`
rewrites the whole file through :func:`~mlsgalerkin.io.files.atomic_write`, so a reader
(or a crash) never sees a partial line. The first line is the header (the column names);
integers are written as such and floats with ``repr``, which round-trips every double exactly
(``nan``, ``inf`` and ``-inf`` included); ``None`` is an empty cell, read back as ``nan``.

>>> format_value(0.1 + 0.2), format_value(7), format_value(None), format_value(float("inf"))
('0.30000000000000004', '7', '', 'inf')
"""

from __future__ import annotations

import csv
import io
import logging
import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from mlsgalerkin.io.files import atomic_write

__all__ = ["TimeSeriesWriter", "columns_of", "format_value", "read_timeseries"]

logger = logging.getLogger(__name__)

Number = int | float


def format_value(value: Any) -> str:
    """One CSV cell: ``None`` empty, integers and bools as integers, floats by ``repr``."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return str(int(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    raise ValueError(
        f"time-series value {value!r} has type {type(value).__name__}; only numbers "
        "(int, float, bool, numpy scalars) or None are allowed"
    )


def _parse_cell(text: str) -> Number | None:
    text = text.strip()
    if text == "":
        return None
    try:
        return int(text)
    except ValueError:
        return float(text)


def _read_csv(path: Path) -> tuple[list[str], list[list[Number | None]]]:
    if not path.is_file():
        raise FileNotFoundError(f"time-series file {path} does not exist")
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        try:
            header = next(reader)
        except StopIteration:
            raise ValueError(f"time-series file {path} is empty (no header line)") from None
        rows = []
        for lineno, cells in enumerate(reader, start=2):
            if not cells:
                continue
            if len(cells) != len(header):
                raise ValueError(
                    f"{path}, line {lineno}: {len(cells)} cells but the header has "
                    f"{len(header)} columns; the file is damaged or not a time series"
                )
            try:
                rows.append([_parse_cell(c) for c in cells])
            except ValueError as exc:
                raise ValueError(f"{path}, line {lineno}: non-numeric cell ({exc})") from exc
    return header, rows


def read_timeseries(path: str | Path) -> dict[str, np.ndarray]:
    """Read a CSV time series into one array per column.

    Returns
    -------
    dict of str to ndarray, each of shape (n_rows,)
        In header order. A column whose cells are all integers is ``int64``, any other
        ``float64`` (empty cells are ``nan``).
    """
    header, rows = _read_csv(Path(path))
    return columns_of(header, rows)


def columns_of(header: Sequence[str], rows: Sequence[Sequence[Number | None]]) -> dict[str, np.ndarray]:
    """Rows of numbers as one array per column, typed as :func:`read_timeseries` does."""
    out: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        col = [r[j] for r in rows]
        if col and all(isinstance(v, int) for v in col):
            out[name] = np.array(col, dtype=np.int64)
        else:
            out[name] = np.array([math.nan if v is None else v for v in col], dtype=np.float64)
    return out


class TimeSeriesWriter:
    """Rows of numbers kept in memory and written as a CSV file by :meth:`flush`.

    Parameters
    ----------
    path : str or Path
        The CSV file (its directory is created on the first flush).
    columns : list of str
        Column names, unique and non-empty; the header line.
    """

    def __init__(self, path: str | Path, columns: Sequence[str]) -> None:
        cols = list(columns) if not isinstance(columns, str) else None
        if not cols or not all(isinstance(c, str) and c for c in cols):
            raise ValueError(
                f"TimeSeriesWriter columns must be a non-empty list of non-empty str, "
                f"got {columns!r}"
            )
        if len(set(cols)) != len(cols):
            dup = sorted({c for c in cols if cols.count(c) > 1})
            raise ValueError(f"TimeSeriesWriter columns must be unique; repeated: {dup}")
        self.path = Path(path)
        self.columns: list[str] = cols
        self._rows: list[tuple[Number | None, ...]] = []

    @property
    def rows(self) -> list[dict[str, Number | None]]:
        """The rows so far, as dicts of column name to value (a copy)."""
        return [dict(zip(self.columns, r)) for r in self._rows]

    def __len__(self) -> int:
        return len(self._rows)

    def append(self, row: Mapping[str, Any] | Sequence[Any]) -> None:
        """Add one row (in memory; call :meth:`flush` to write the file).

        Parameters
        ----------
        row : dict or sequence
            A dict with exactly the columns as keys (``None`` for a missing value), or a
            sequence of one value per column in column order. Values are numbers.
        """
        if isinstance(row, Mapping):
            missing = [c for c in self.columns if c not in row]
            extra = [k for k in row if k not in self.columns]
            if missing or extra:
                raise ValueError(
                    f"time-series row keys do not match the columns {self.columns}: missing "
                    f"{missing}, unknown {extra} (pass None for a value not available)"
                )
            values = [row[c] for c in self.columns]
        elif isinstance(row, (str, bytes)):
            raise ValueError("time-series row must be a dict or a sequence of numbers, not str")
        else:
            values = list(row)
            if len(values) != len(self.columns):
                raise ValueError(
                    f"time-series row has {len(values)} values but there are "
                    f"{len(self.columns)} columns {self.columns}"
                )
        for c, v in zip(self.columns, values):
            try:
                format_value(v)
            except ValueError as exc:
                raise ValueError(f"column {c!r}: {exc}") from None
        self._rows.append(tuple(_plain(v) for v in values))

    def text(self) -> str:
        """The CSV text :meth:`flush` writes (header line, then one line per row)."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.columns)
        for r in self._rows:
            w.writerow([format_value(v) for v in r])
        return buf.getvalue()

    def flush(self) -> Path:
        """Rewrite the whole file atomically with all rows so far; returns the path."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(self.path, self.text())
        return self.path

    @classmethod
    def resume(
        cls,
        path: str | Path,
        after_time: float | None,
        time_column: str = "time",
        columns: Sequence[str] | None = None,
    ) -> TimeSeriesWriter:
        """Continue an existing CSV, e.g. in a run restarted from a checkpoint.

        Reads ``path`` and keeps the rows with ``row[time_column] <= after_time`` (all rows if
        ``after_time`` is None), dropping what the interrupted run wrote after the checkpoint.
        Nothing is written until the next :meth:`flush`.

        Parameters
        ----------
        path : str or Path
            The CSV file.
        after_time : float or None
            Restart time [s].
        time_column : str
            Name of the time column.
        columns : list of str, optional
            Expected columns. If given, the file's header must match them, and a missing file
            gives an empty writer with these columns instead of FileNotFoundError.
        """
        path = Path(path)
        if not path.is_file() and columns is not None:
            logger.info("no %s to resume; starting a new time series", path)
            return cls(path, columns)
        header, rows = _read_csv(path)
        if columns is not None and list(columns) != header:
            raise ValueError(
                f"{path} has columns {header} but {list(columns)} were expected; write to a "
                "new file or pass the matching columns"
            )
        writer = cls(path, header)
        if after_time is not None:
            if time_column not in header:
                raise ValueError(
                    f"{path} has no column {time_column!r} (columns: {header}); pass "
                    "time_column= naming the time column"
                )
            j = header.index(time_column)
            t_max = float(after_time)
            rows = [r for r in rows if r[j] is None or not r[j] > t_max]
        writer._rows = [tuple(r) for r in rows]
        return writer


def _plain(v: Any) -> Number | None:
    """``v`` as a Python int/float (numpy scalars and bools converted)."""
    if v is None:
        return None
    if isinstance(v, (bool, np.bool_)):
        return int(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    return float(v)
