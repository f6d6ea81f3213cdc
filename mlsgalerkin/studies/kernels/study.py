"""Run the kernel study on the study engine and write its tables, work-precision plot and
provenance. The full report (``summary.md``, the study's figures) is written by
``verification/kernel_study.py``."""

from __future__ import annotations

import functools
import logging
import time
from pathlib import Path
from typing import Any

from mlsgalerkin.io.files import write_csv_rows, write_json
from mlsgalerkin.io.provenance import provenance
from mlsgalerkin.studies.engine import Grid, numeric_environment, run_study
from mlsgalerkin.studies.kernels.config import COLUMNS, FIT_COLUMNS, StudyConfig, make_config
from mlsgalerkin.studies.kernels.fits import compute_fits
from mlsgalerkin.studies.kernels.headline import headline
from mlsgalerkin.studies.kernels.meshfree import measure_mls_1d, measure_mls_2d, mls_points, warm_up
from mlsgalerkin.studies.kernels.output import csv_cells
from mlsgalerkin.studies.kernels.result import KernelStudyResult
from mlsgalerkin.studies.kernels.sph import measure_integral, measure_particle, sph_points

__all__ = ["measure_point", "run_kernel_study", "study_grid"]

logger = logging.getLogger(__name__)

#: The rows as they are measured (kept if the study stops early; removed once the table is written).
ROWS_LOG = "kernel_study.rows.jsonl"


def study_grid(cfg: StudyConfig) -> Grid:
    """Every point of the study: the SPH sweeps (part 1), then the shape-function sweeps."""
    return Grid.from_points(sph_points(cfg) + mls_points(cfg))


def measure_point(
    cfg: StudyConfig,
    *,
    part: str,
    approximation: str,
    kernel: str,
    sweep: str,
    h: float | None = None,
    n_neighbors: int | None = None,
    n_particles: int | None = None,
    layout: str | None = None,
    h_over_dx: float | None = None,
    n_side: int | None = None,
) -> list[dict[str, Any]]:
    """The rows (one per function and region) of one grid point of :func:`study_grid`."""
    if part == "sph" and approximation == "integral":
        return measure_integral(cfg, kernel, sweep, h, n_neighbors)
    if part == "sph":
        return measure_particle(cfg, kernel, sweep, h, n_particles)
    if part == "mls1d":
        return measure_mls_1d(cfg, approximation, kernel, sweep, n_particles, h)
    if part == "mls2d":
        return measure_mls_2d(cfg, approximation, layout, kernel, sweep, h_over_dx, n_side)
    raise ValueError(f"unknown part {part!r}; the study has parts 'sph', 'mls1d' and 'mls2d'")


def run_kernel_study(
    out: str | Path, quick: bool = False, *, scheduler: Any = None, progress: bool = True
) -> KernelStudyResult:
    """Run the study and write ``kernel_study.csv``, ``kernel_study_fits.csv``,
    ``work_precision.png`` and ``provenance.json``.

    Parameters
    ----------
    out : output directory (created if needed).
    quick : fewer sweep points (the whole run takes well under 30 s).
    scheduler : where the grid runs (:func:`~mlsgalerkin.studies.engine.run_study`): ``None``
        for a local Dask cluster, ``"serial"``, or a Dask scheduler address.
    progress : show a tqdm progress bar over the measured points.
    """
    t_start = time.perf_counter()
    cfg = make_config(quick)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    study = run_study(
        study_grid(cfg),
        functools.partial(measure_point, cfg),
        scheduler=scheduler,
        warm_up=functools.partial(warm_up, cfg),
        numba_threads=cfg.threads,
        progress=progress,
        rows_log=out / ROWS_LOG,
        description="kernel study",
    )
    rows = study.records
    fits = compute_fits(rows)
    csv_path = write_csv_rows(out / "kernel_study.csv", COLUMNS, csv_cells(rows, COLUMNS))
    (out / ROWS_LOG).unlink(missing_ok=True)  # the table holds every row now
    fits_path = write_csv_rows(out / "kernel_study_fits.csv", FIT_COLUMNS,
                               csv_cells(fits, FIT_COLUMNS))
    kernel_2d = cfg.kernels_2d[0]
    plot = study.work_precision_plot(
        out / "work_precision.png",
        error="error_abs",
        by=("approximation", "layout"),
        time="wall_s",
        where={"part": "mls2d", "sweep": "resolution", "region": "interior",
               "kernel": kernel_2d},
        title=f"2D {kernel_2d}, u = sin(πx)cos(πy) + xy², h = {cfg.ratio_fixed_2d:g} Δx, "
              f"n = {min(cfg.levels_2d)}² … {max(cfg.levels_2d)}² nodes",
        error_label="RMS error of u, interior points [-]",
        time_label="wall time: shape functions + apply [s]",
    )
    wall = time.perf_counter() - t_start
    prov = provenance("kernel_study", mode="quick" if quick else "full", extra={
        "seed": cfg.seed,
        "numba_threads": cfg.threads,
        "scheduler": study.scheduler,
        "workers": study.workers,
        "environment": numeric_environment(),
        "measure_s": round(study.wall_time_s, 2),
        "wall_s": round(wall, 2),
        "n_rows": len(rows),
        "call": {"out": str(out), "quick": quick, "progress": progress},
    })
    prov_path = write_json(out / "provenance.json", prov)
    logger.info("kernel study finished in %.1f s", wall)
    return KernelStudyResult(out=out, config=cfg, csv_path=csv_path, fits_path=fits_path,
                             provenance_path=prov_path, plots=[plot], rows=rows, fits=fits,
                             headline=headline(rows, fits, cfg), provenance=prov, study=study,
                             wall_s=wall)
