"""The records of a study and what a researcher does with them: select, CSV, fits, plot.

A record is a flat dict: the point's parameters, the measures, ``wall_time_s`` and ``worker``
(see :mod:`~mlsgalerkin.studies.engine.runner`). Power-law fits go through
:func:`mlsgalerkin.analysis.convergence.fit_power_law`.

>>> result = StudyResult(records=[{"h": h, "err": 3 * h**2, "wall_time_s": 1 / h}
...                               for h in (0.4, 0.2, 0.1)], parameters=("h",))
>>> fit = result.fit(x="h", y="err")[0]
>>> round(fit["exponent"], 6), round(fit["coefficient"], 6), fit["n_points"]
(2.0, 3.0, 3)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mlsgalerkin.analysis.convergence import ROUNDOFF, fit_power_law
from mlsgalerkin.io.files import format_cell, write_csv_rows
from mlsgalerkin.studies.engine.timing import TimingPolicy
from mlsgalerkin.studies.figures import PLOT_FLOOR, save_png, tidy_log_axes

__all__ = ["FIT_COLUMNS", "StudyResult", "select", "write_records"]

_MARKERS = "os^vD<>ph*"
#: Columns of a fit record after the ``by`` columns (see :meth:`StudyResult.fit`).
FIT_COLUMNS = ("x", "y", "exponent", "coefficient", "r2", "n_points", "x_min", "x_max")


def _is_scalar(v: Any) -> bool:
    return v is None or isinstance(v, (str, bool, int, float, np.generic))


def select(records: Iterable[Mapping[str, Any]], where: Mapping[str, Any] | None = None
           ) -> list[Mapping[str, Any]]:
    """The records whose columns equal every ``name: value`` of ``where`` (all if ``None``)."""
    where = dict(where or {})
    return [r for r in records if all(k in r and r[k] == v for k, v in where.items())]


def write_records(path: str | Path, records: Sequence[Mapping[str, Any]],
                  columns: Sequence[str] | None = None, *, digits: int = 6,
                  nan: str = "nan") -> Path:
    """Write records as CSV atomically; returns the path.

    ``columns`` default: every column whose values are all scalars (strings, numbers, booleans,
    ``None``), in order of first appearance; arrays and other objects are left out. Floats get
    ``digits`` significant digits (:func:`mlsgalerkin.io.files.format_cell`), missing values are
    empty.
    """
    if columns is None:
        names = dict.fromkeys(k for r in records for k in r)
        columns = [c for c in names if all(_is_scalar(r.get(c)) for r in records)]
    cells = ([format_cell(r.get(c), digits=digits, nan=nan) for c in columns] for r in records)
    return write_csv_rows(path, list(columns), cells)


def _group_key(record: Mapping[str, Any], by: Sequence[str]) -> tuple:
    return tuple(record.get(b) for b in by)


def _groups(records: Iterable[Mapping[str, Any]], by: Sequence[str]) -> dict[tuple, list]:
    groups: dict[tuple, list] = {}
    for r in records:
        groups.setdefault(_group_key(r, by), []).append(r)
    return groups


@dataclass
class StudyResult:
    """Records of one study run, sorted by grid index; see the module docstring.

    ``parameters`` are the grid's parameter names, ``scheduler`` says where the grid ran,
    ``timing`` is the timing policy and ``wall_time_s`` the elapsed time of the whole run.
    """

    records: list[dict[str, Any]] = field(repr=False)
    parameters: tuple[str, ...] = ()
    scheduler: str = ""
    timing: TimingPolicy = field(default_factory=TimingPolicy)
    wall_time_s: float = math.nan

    @property
    def workers(self) -> list[str]:
        """The workers that measured the records, in order of first appearance."""
        return list(dict.fromkeys(r["worker"] for r in self.records if "worker" in r))

    def select(self, **where: Any) -> list[dict[str, Any]]:
        """The records whose columns equal every ``name=value`` given."""
        return select(self.records, where)  # type: ignore[return-value]

    def to_csv(self, path: str | Path, columns: Sequence[str] | None = None, *,
               digits: int = 6) -> Path:
        """Write the records as CSV atomically (see :func:`write_records`)."""
        return write_records(path, self.records, columns, digits=digits)

    def _check_columns(self, names: Iterable[str]) -> None:
        known = dict.fromkeys(k for r in self.records for k in r)
        missing = [n for n in names if n not in known]
        if missing:
            raise KeyError(f"no column {', '.join(map(repr, missing))} in the records; "
                           f"columns are {', '.join(known)}")

    def fit(self, x: str, y: str | Sequence[str], by: Sequence[str] = (),
            where: Mapping[str, Any] | None = None, *, floor: float = ROUNDOFF,
            min_points: int = 3) -> list[dict[str, Any]]:
        """Power law ``y = C x**p`` per group of equal ``by`` columns, for each ``y`` column.

        The fit is :func:`~mlsgalerkin.analysis.convergence.fit_power_law` (least squares in
        log-log over the group's records, skipping ``y <= floor`` and non-finite values); with
        ``x`` a spacing, ``exponent`` is the observed order of convergence. Returns one dict per
        group and ``y`` column, groups in order of first appearance: the ``by`` values, then
        :data:`FIT_COLUMNS` (``exponent`` NaN when fewer than ``min_points`` usable points).
        """
        ys = [y] if isinstance(y, str) else list(y)
        by = list(by)
        self._check_columns([x, *ys, *by, *(where or {})])
        out = []
        for key, rs in _groups(select(self.records, where), by).items():
            for q in ys:
                f = fit_power_law([r[x] for r in rs], [r[q] for r in rs], floor=floor,
                                  min_points=min_points)
                out.append({**dict(zip(by, key)), "x": x, "y": q, "exponent": f.exponent,
                            "coefficient": f.coefficient, "r2": f.r2, "n_points": f.n_points,
                            "x_min": f.x_min, "x_max": f.x_max})
        return out

    def work_precision_plot(self, path: str | Path, error: str, by: Sequence[str] = (),
                            time: str = "wall_time_s", where: Mapping[str, Any] | None = None,
                            *, title: str | None = None, error_label: str | None = None,
                            time_label: str | None = None) -> Path:
        """Error against wall time, log-log, one line per group of equal ``by`` columns.

        Lower-left is better: a point shows what an accuracy cost. ``time`` is the timing
        column (default the engine's ``wall_time_s``, seconds per measurement); each line joins
        its points in grid order (e.g. coarse to fine); errors are clipped to
        :data:`~mlsgalerkin.studies.figures.PLOT_FLOOR`. The PNG is written atomically (Agg
        backend); returns its path.
        """
        by = list(by)
        self._check_columns([error, time, *by, *(where or {})])
        groups = _groups(select(self.records, where), by)
        if not groups:
            raise ValueError(f"no record matches where={dict(where or {})}; nothing to plot")
        from matplotlib.figure import Figure

        many = len(groups) > 6  # legend beside the axes, not over the lines
        fig = Figure(figsize=(9.6 if many else 6.4, 4.6))
        ax = fig.subplots()
        for i, (key, rs) in enumerate(groups.items()):
            pts = [(float(r[time]), float(r[error])) for r in rs
                   if r[time] is not None and r[error] is not None
                   and math.isfinite(float(r[time])) and float(r[time]) > 0
                   and math.isfinite(float(r[error]))]
            if not pts:
                continue
            t, e = np.array(pts).T
            label = ", ".join(f"{b}={v}" for b, v in zip(by, key)) or error
            ax.loglog(t, np.maximum(e, PLOT_FLOOR), color=f"C{i % 10}",
                      ls=("-", "--", ":")[i // 10 % 3], marker=_MARKERS[i % len(_MARKERS)],
                      ms=4, lw=1.2, label=label)
        ax.set_xlabel(time_label or f"wall time per measurement, {time} [s]")
        ax.set_ylabel(error_label or f"{error} [-]")
        ax.set_title(title or "Work-precision: error against wall time (lower-left is better)",
                     fontsize=9)
        ax.grid(True, which="both", alpha=0.25)
        if len(groups) > 1 or by:
            if many:
                ax.legend(fontsize=7, frameon=False, loc="upper left", bbox_to_anchor=(1.02, 1.0))
            else:
                ax.legend(fontsize=7, frameon=False)
        tidy_log_axes(ax)
        fig.tight_layout()
        return save_png(fig, path)
