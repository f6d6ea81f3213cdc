"""The Galerkin study's report: tables, measured observations, ``summary.md`` and figures.

The numbers come from :func:`mlsgalerkin.studies.galerkin.run_galerkin_study` (tables, orders,
provenance, the engine's work-precision plot); :func:`write_report` adds to its output directory
``summary.md`` and ``convergence_<problem>.png``, ``work_precision.png`` (replacing the engine's
single-panel plot), ``wall_split.png``, ``h_sweep_<problem>.png`` and ``spectra.png``.

Modules: ``plots`` (figures and labels), ``observations`` (measured statements),
``summary`` (tables and the Markdown).
"""

from __future__ import annotations

import logging
from pathlib import Path

from mlsgalerkin.io.files import atomic_write, write_json
from mlsgalerkin.studies.galerkin import GalerkinStudyResult

from .plots import make_plots
from .summary import summary_markdown

__all__ = ["write_report"]

logger = logging.getLogger(__name__)


def write_report(result: GalerkinStudyResult) -> list[Path]:
    """Write ``summary.md`` and the study's figures next to ``result``'s tables; returns the
    figure paths."""
    plots = make_plots(result.rows, result.config, result.out)
    prov = dict(result.provenance, report="verification/galerkin_convergence.py")
    files = {"csv": result.csv_path.name, "orders": result.orders_path.name,
             "provenance": result.provenance_path.name, **{p.stem: p.name for p in plots},
             "summary": "summary.md"}
    atomic_write(result.out / "summary.md",
                 summary_markdown(result.rows, result.orders, result.config, prov, files))
    write_json(result.provenance_path, prov)
    logger.info("Galerkin report: %d figures and summary.md", len(plots))
    return plots
