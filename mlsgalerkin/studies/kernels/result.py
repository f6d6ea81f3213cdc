"""What a kernel-study run returns: its files, rows, fits, key numbers and a console report."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mlsgalerkin.studies.engine.result import StudyResult
from mlsgalerkin.studies.kernels.config import SMOOTH_FUNCTIONS, StudyConfig

__all__ = ["KernelStudyResult"]


@dataclass
class KernelStudyResult:
    """Paths, rows, fits and key numbers (:mod:`~.headline`) of one run.

    ``rows`` are the engine's records (CSV columns plus the grid parameters, ``rank_note`` and
    ``wall_time_s``); ``provenance`` is the dict written to ``provenance.json``.
    """

    out: Path
    config: StudyConfig = field(repr=False)
    csv_path: Path
    fits_path: Path
    provenance_path: Path
    plots: list[Path]
    rows: list[dict[str, Any]] = field(repr=False)
    fits: list[dict[str, Any]] = field(repr=False)
    headline: dict[str, Any] = field(repr=False)
    provenance: dict[str, Any] = field(repr=False)
    study: StudyResult = field(repr=False)
    wall_s: float = math.nan

    @property
    def quick(self) -> bool:
        """Whether this was the quick configuration."""
        return self.config.quick

    @property
    def notes(self) -> list[str]:
        """Points whose moment matrix was accepted while singular (rank check), one sentence
        each."""
        return list(dict.fromkeys(r["rank_note"] for r in self.rows if r.get("rank_note")))

    def report(self) -> str:
        """Text for the terminal: files, where it ran, slopes, 5-neighbour errors, 2D orders."""
        lines = [
            f"kernel study ({'quick' if self.quick else 'full'}) written to {self.out} "
            f"in {self.wall_s:.1f} s on {self.study.scheduler}",
            f"  table     : {self.csv_path} ({len(self.rows)} rows)",
            f"  fits      : {self.fits_path}",
            f"  provenance: {self.provenance_path} (commit {self.provenance['git_commit']})",
            "  plots     : " + ", ".join(p.name for p in self.plots),
            "",
            "fitted slope beta (error ~ h^beta), integral approximation, "
            f"N_nb = {self.config.int_nnb_fixed}, interior:",
        ]
        funcs = list(SMOOTH_FUNCTIONS)
        lines.append(f"  {'kernel':<18}" + "".join(f"{f:>10}" for f in funcs))
        for k, vals in self.headline["beta_integral"].items():
            lines.append(f"  {k:<18}" + "".join(f"{vals.get(f, math.nan):>10.2f}" for f in funcs))
        b5 = self.headline["worst_rel_5nb"]
        if b5:
            bad = [k for k, v in b5.items() if not v < 0.05]
            lines.append(
                f"  5 neighbours at h = {self.config.int_h_fixed:g}: worst relative error over "
                "F1-F4 " + ", ".join(f"{k} {100 * v:.2f}%" for k, v in b5.items())
            )
            lines.append(f"  kernels above 5%: {', '.join(bad) if bad else 'none'}")
        orders = self.headline.get("orders_2d")
        if orders:
            lines.append("observed 2D orders in dx (jittered lattice, interior, h/dx fixed):")
            for key, (pv, pg) in orders.items():
                lines.append(f"  {key:<28} value {pv:5.2f}   gradient {pg:5.2f}")
        return "\n".join(lines)
