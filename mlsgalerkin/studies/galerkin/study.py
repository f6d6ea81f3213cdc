"""Run the Galerkin study on the study engine and write its tables, work-precision plot and
provenance. The full report (``summary.md``, the study's figures) is written by
``verification/galerkin_convergence.py``."""

from __future__ import annotations

import functools
import logging
import time
from pathlib import Path
from typing import Any

from mlsgalerkin.io.files import write_json
from mlsgalerkin.io.provenance import provenance
from mlsgalerkin.studies.engine import Grid, numeric_environment, run_study, write_records
from mlsgalerkin.studies.galerkin.result import GalerkinStudyResult
from mlsgalerkin.studies.galerkin.sweeps import (
    fit_orders,
    make_config,
    measure_solve,
    study_points,
    warm_up,
    warm_up_specs,
)

__all__ = ["COLUMNS", "ORDER_COLUMNS", "run_galerkin_study"]

logger = logging.getLogger(__name__)

#: Columns of ``galerkin_convergence.csv`` (one row per solve).
COLUMNS = [
    "study", "problem", "rule", "basis", "kernel", "support_ratio", "dilation", "spacing",
    "n_nodes", "n_dofs", "nodes", "bc", "error_l2", "error_h1", "error_energy", "error_h1_rule",
    "wall_s",
    "wall_shape_s", "wall_assembly_s", "wall_solve_s", "wall_error_s", "neighbors_mean",
    "n_fallback", "finite", "n_rigid", "n_zero_modes", "n_spurious_modes", "eig_below",
    "eig_above", "eig_gap", "eig_first", "eig_tol", "spectrum", "energy_ratio_max",
    "n_soft_modes", "nitsche_ci", "worker",
]
#: Columns of ``galerkin_orders.csv`` (one row per convergence series).
ORDER_COLUMNS = [
    "problem", "rule", "basis", "kernel", "nodes", "support_ratio", "n_levels", "spacing_max",
    "spacing_min", "n_nodes_max", "order_l2", "order_l2_last", "order_h1", "order_h1_last",
    "order_energy", "order_energy_last", "order_h1_rule", "order_h1_rule_last",
    "error_l2_finest", "error_h1_finest",
    "error_energy_finest", "error_h1_rule_finest", "wall_s_finest",
]

#: The rows as they are measured (kept if the study stops early; removed once the table is written).
ROWS_LOG = "galerkin_convergence.rows.jsonl"


def run_galerkin_study(out: str | Path, quick: bool = False, *, scheduler: Any = None,
                       progress: bool = True) -> GalerkinStudyResult:
    """Patch tests, convergence orders, smoothing-length sweep and work-precision data.

    Parameters
    ----------
    out : output directory (created if needed).
    quick : three refinement levels, one kernel, a short sweep (well under a minute).
    scheduler : where the grid runs (:func:`~mlsgalerkin.studies.engine.run_study`): ``None``
        for a local Dask cluster, ``"serial"``, or a Dask scheduler address.
    progress : show a tqdm progress bar over the solves.

    Writes ``galerkin_convergence.csv`` (one row per solve), ``galerkin_orders.csv`` (observed
    orders per series), ``work_precision.png`` and ``provenance.json``.
    """
    t_start = time.perf_counter()
    cfg = make_config(quick)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    study = run_study(
        Grid.from_points(study_points(cfg)),
        functools.partial(measure_solve, cfg),
        scheduler=scheduler,
        warm_up=functools.partial(warm_up, tuple(warm_up_specs(cfg))),
        numba_threads=cfg.threads,
        progress=progress,
        rows_log=out / ROWS_LOG,
        description="galerkin study",
    )
    rows = study.records
    orders = fit_orders(rows)
    csv_path = write_records(out / "galerkin_convergence.csv", rows, COLUMNS)
    (out / ROWS_LOG).unlink(missing_ok=True)  # the table holds every row now
    orders_path = write_records(out / "galerkin_orders.csv", orders, ORDER_COLUMNS)
    kernel = cfg.kernels[0]
    plot = study.work_precision_plot(
        out / "work_precision.png",
        error="error_l2",
        by=("problem", "rule", "basis"),
        time="wall_s",
        where={"study": "convergence", "kernel": kernel, "nodes": "regular"},
        title=f"Galerkin convergence series ({kernel}, regular nodes), coarse to fine",
        error_label="relative L2 error [-]",
        time_label="wall time: shape functions + assembly + solve [s]",
    )
    wall = time.perf_counter() - t_start
    import scipy

    prov = provenance("galerkin_convergence", mode="quick" if quick else "default", extra={
        "scipy": scipy.__version__,
        "wall_s": round(wall, 1),
        "measure_s": round(study.wall_time_s, 1),
        "numba_threads": cfg.threads,
        "scheduler": study.scheduler,
        "workers": study.workers,
        "environment": numeric_environment(),
        "n_solves": len(rows),
        "seed": cfg.seed,
        "call": {"out": str(out), "quick": quick, "progress": progress},
    })
    prov_path = write_json(out / "provenance.json", prov)
    logger.info("Galerkin study finished in %.1f s", wall)
    return GalerkinStudyResult(out=out, config=cfg, csv_path=csv_path, orders_path=orders_path,
                               provenance_path=prov_path, plots=[plot], rows=rows, orders=orders,
                               provenance=prov, study=study, wall_s=wall)
