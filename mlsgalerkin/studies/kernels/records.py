"""Results of the kernel study: the measured rows, the run summary and row selection."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mlsgalerkin.studies.kernels.config import SMOOTH_FUNCTIONS
from mlsgalerkin.studies.kernels.measure import rms_error

__all__ = ["PLOT_FLOOR", "KernelStudyResult", "Recorder", "select_rows", "xy_points"]


@dataclass
class KernelStudyResult:
    """Paths, fitted slopes and headline numbers of one run; :meth:`report` summarises them."""

    out: Path
    quick: bool
    csv_path: Path
    fits_path: Path
    summary_path: Path
    provenance_path: Path
    plots: list[Path]
    rows: list[dict] = field(repr=False)
    fits: list[dict] = field(repr=False)
    headline: dict
    wall_s: float

    def report(self) -> str:
        """Text for the terminal: output files, headline slopes, 5-neighbour errors, 2D orders."""
        lines = [
            f"kernel study ({'quick' if self.quick else 'full'}) written to {self.out} "
            f"in {self.wall_s:.1f} s",
            f"  table    : {self.csv_path} ({len(self.rows)} rows)",
            f"  fits     : {self.fits_path}",
            f"  summary  : {self.summary_path}",
            f"  provenance: {self.provenance_path}",
            "  plots    : " + ", ".join(p.name for p in self.plots),
            "",
            "fitted slope beta (error ~ h^beta), integral approximation, N_nb = 100, interior:",
        ]
        hb = self.headline.get("beta_integral", {})
        funcs = list(SMOOTH_FUNCTIONS)
        lines.append(f"  {'kernel':<18}" + "".join(f"{f:>10}" for f in funcs))
        for k, vals in hb.items():
            lines.append(f"  {k:<18}" + "".join(f"{vals.get(f, math.nan):>10.2f}" for f in funcs))
        b5 = self.headline.get("worst_rel_5nb")
        if b5:
            bad = [k for k, v in b5.items() if not v < 0.05]
            lines.append(
                "  5 neighbours at h = 0.1: worst relative error over F1-F4 "
                + ", ".join(f"{k} {100 * v:.2f}%" for k, v in b5.items())
            )
            lines.append(f"  kernels above 5%: {', '.join(bad) if bad else 'none'}")
        orders = self.headline.get("orders_2d")
        if orders:
            lines.append("observed 2D orders in dx (jittered lattice, interior, h/dx fixed):")
            for key, (pv, pg) in orders.items():
                lines.append(f"  {key:<28} value {pv:5.2f}   gradient {pg:5.2f}")
        if self.headline.get("part2_skipped"):
            lines.append(
                "part 2 (shape functions) skipped: mlsgalerkin.shape_functions unavailable"
            )
        return "\n".join(lines)


class Recorder:
    """Collects the measured rows (one per region) and notes; drives the progress bar."""

    def __init__(self, progress: bool, total: int):
        self.rows: list[dict] = []
        self.notes: list[str] = []
        self.bar = None
        if progress:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=total, desc="kernel study", unit="pt", leave=False)

    def tick(self, n: int = 1) -> None:
        """Advance the progress bar by ``n`` measured points."""
        if self.bar is not None:
            self.bar.update(n)

    def close(self) -> None:
        """Close the progress bar."""
        if self.bar is not None:
            self.bar.close()

    def add(
        self,
        base: dict,
        masks: dict[str, np.ndarray],
        approx,
        exact,
        *,
        wall_s: float,
        counts: np.ndarray | float | None = None,
        grad=None,
        grad_exact=None,
        cond: np.ndarray | None = None,
    ) -> None:
        """Append one row per non-empty region of ``masks``: ``base`` plus the RMS errors of
        ``approx`` (and ``grad``) against the exact values, the largest condition number, the
        mean neighbour count and ``wall_s``.
        """
        gerr = None if grad is None else np.linalg.norm(np.asarray(grad) - grad_exact, axis=1)
        for region, mask in masks.items():
            if not np.any(mask):
                continue
            ea, er = rms_error(approx, exact, mask)
            ga = gr = gm = cm = math.nan
            if grad is not None:
                ga, gr = rms_error(grad, grad_exact, mask)
                gm = float(gerr[mask].max())
            if cond is not None:
                cm = float(np.max(cond[mask]))
            if isinstance(counts, np.ndarray):
                nnb = float(np.mean(counts[mask]))
            else:
                nnb = counts
            row = dict(base)
            row.update(
                region=region,
                n_eval=int(np.count_nonzero(mask)),
                error_abs=ea,
                error_rel=er,
                error_grad=ga,
                error_grad_rel=gr,
                error_grad_max=gm,
                cond_max=cm,
                n_neighbors=nnb,
                wall_s=wall_s,
            )
            self.rows.append(row)


# --------------------------------------------------------------------------------------
# row selection (plots and analysis)
# --------------------------------------------------------------------------------------


#: Errors are clipped to this before they are plotted on log axes.
PLOT_FLOOR = 1e-17


def select_rows(rows: list[dict], **sel) -> list[dict]:
    """The rows whose fields equal every ``key=value`` of ``sel``."""
    rs = [r for r in rows if all(r[k] == v for k, v in sel.items())]
    return rs


def xy_points(rs: list[dict], xname: str, yname: str) -> tuple[np.ndarray, np.ndarray]:
    """``(x, y)`` of the rows with a finite ``yname``, sorted by x; y clipped to
    :data:`PLOT_FLOOR`."""
    pairs = sorted(
        (r[xname], r[yname]) for r in rs if r[yname] is not None and np.isfinite(r[yname])
    )
    if not pairs:
        return np.array([]), np.array([])
    x, y = map(np.asarray, zip(*pairs))
    return x, np.maximum(y, PLOT_FLOOR)
