"""What a kernel-study run returns: its files, rows, fits, key numbers and a console report."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mlsgalerkin.studies.kernels.config import SMOOTH_FUNCTIONS
from mlsgalerkin.studies.run import StudyRun

__all__ = ["KernelStudyResult"]


@dataclass
class KernelStudyResult(StudyRun):
    """A kernel-study run (:class:`~mlsgalerkin.studies.run.StudyRun`) with its fits and key
    numbers (:mod:`~.headline`). ``rows`` carry the CSV columns plus the grid parameters,
    ``rank_note`` and ``wall_time_s``."""

    fits_path: Path = field(kw_only=True)
    fits: list[dict[str, Any]] = field(kw_only=True, repr=False)
    headline: dict[str, Any] = field(kw_only=True, repr=False)

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
            *self.files_lines({"fits": self.fits_path}),
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
