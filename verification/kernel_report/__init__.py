"""The kernel study's report: Xing's (2019) claims, the MLS findings, ``summary.md``, figures.

The numbers come from :func:`mlsgalerkin.studies.kernels.run_kernel_study` (tables, fits,
provenance, the engine's work-precision plot); :func:`write_report` adds to its output directory

``summary.md``                   provenance, set-up, slope tables, claims (a)-(d), part 2
``sph_error_vs_h.png``           part 1: error against h
``sph_error_vs_neighbors.png``   part 1: error against neighbour and particle count
``mls1d_errors.png``             part 2: 1D sweeps
``mls2d_error_vs_h.png``         part 2: 2D error against h/Δx
``mls2d_error_vs_dx.png``        part 2: 2D error against Δx
``work_precision.png``           error against wall time along the refinement sweeps (replaces
                                 the engine's single-panel plot)

Modules: ``claims`` (the numbers behind the claims), ``rows`` (row selection), ``style`` and
``plots`` (figures), ``summary`` and ``summary_meshfree`` (the Markdown).
"""

from __future__ import annotations

import logging
from pathlib import Path

from mlsgalerkin.io.files import atomic_write, write_json
from mlsgalerkin.studies.kernels import KernelStudyResult

from .claims import analyse, kernel_diagnostics
from .plots import plots_shape_functions, plots_sph
from .summary import summary_text
from .summary_meshfree import findings

__all__ = ["analyse", "kernel_diagnostics", "write_report"]

logger = logging.getLogger(__name__)


def write_report(result: KernelStudyResult) -> list[Path]:
    """Write ``summary.md`` and the study's figures next to ``result``'s tables; returns the
    figure paths (in the order the summary lists them)."""
    cfg, rows = result.config, result.rows
    res = analyse(rows, result.fits, cfg)
    res["findings"] = findings(res, cfg)
    if result.notes:
        res["findings"].append(
            "Rank check (a point needs at least as many neighbours as basis terms for order ≥ 1): "
            + "; ".join(result.notes)
            + ". Such a moment matrix is singular, so the point should "
            "have fallen back to a lower order; its shape-function gradient is not trustworthy."
        )
        for note in result.notes:
            logger.warning("shape functions: %s", note)
    plots = plots_sph(rows, cfg, result.out) + plots_shape_functions(rows, cfg, result.out)
    prov = dict(result.provenance, report="verification/kernel_study.py")
    files = {
        "csv": result.csv_path.name,
        "fits": result.fits_path.name,
        "provenance": result.provenance_path.name,
        **{p.stem: p.name for p in plots},
    }
    atomic_write(result.out / "summary.md", summary_text(res, cfg, prov, files))
    write_json(result.provenance_path, prov)
    return plots
