"""Entry point of the kernel study: run both parts and write the tables, plots and summary."""

from __future__ import annotations

import json
import logging
import time
from pathlib import Path

from mlsgalerkin.io.files import atomic_write, write_csv_rows
from mlsgalerkin.studies.kernels.claims import analyse
from mlsgalerkin.studies.kernels.config import (
    COLUMNS,
    FIT_COLUMNS,
    SMOOTH_FUNCTIONS,
    StudyConfig,
    make_config,
)
from mlsgalerkin.studies.kernels.fits import compute_fits
from mlsgalerkin.studies.kernels.meshfree import (
    Shapes,
    get_shape_functions,
    run_mls_1d,
    run_mls_2d,
    start_prewarm,
    wait_prewarm,
    warm_up,
    warm_up_2d_linear,
)
from mlsgalerkin.studies.kernels.output import csv_cells, provenance
from mlsgalerkin.studies.kernels.plots import plots_shape_functions, plots_sph
from mlsgalerkin.studies.kernels.records import KernelStudyResult, Recorder
from mlsgalerkin.studies.kernels.report import summary_text
from mlsgalerkin.studies.kernels.report_meshfree import findings
from mlsgalerkin.studies.kernels.sph import run_sph

__all__ = ["run_kernel_study"]

logger = logging.getLogger(__name__)


def _n_tasks(cfg: StudyConfig, part2: bool) -> int:
    n = len(cfg.sph_kernels) * (
        len(cfg.int_h) + len(cfg.int_nnb) + len(cfg.part_h) + len(cfg.part_n)
    )
    if part2:
        n += (
            len(cfg.mls_kernels)
            * len(cfg.mls_methods)
            * (len(cfg.part_h) + len(cfg.mls_part_n) + len(cfg.refine_n))
        )
        n += (
            len(cfg.kernels_2d)
            * len(cfg.methods_2d)
            * len(cfg.layouts_2d)
            * (len(cfg.ratios_2d) + len(cfg.levels_2d))
        )
    return n


def run_kernel_study(
    out: str | Path, quick: bool = False, progress: bool = True, prewarm: bool = True
) -> KernelStudyResult:
    """Run the study and write CSV tables, PNG plots, ``summary.md`` and ``provenance.json``.

    Parameters
    ----------
    out : output directory (created if needed).
    quick : fewer sweep points (the whole run takes well under 30 s).
    progress : show a tqdm progress bar over the measured points.
    prewarm : compile the general shape-function kernel in a background process (numba on-disk
        cache) while the SPH part runs; costs nothing when the cache is already warm.
    """
    t_start = time.perf_counter()
    cfg = make_config(quick)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    sf = get_shape_functions()
    shapes = Shapes(sf) if sf is not None else None
    extra: dict = {"part2": shapes is not None}
    # numba compilation (cold cache: tens of seconds) is overlapped with the SPH part: a second
    # process compiles the general shape-function kernel into numba's on-disk cache while this
    # one runs the (pure numpy) SPH sums, compiles the neighbour search and the 2D-linear kernel,
    # and draws the SPH plots. Nothing is timed before every kernel is compiled.
    proc = start_prewarm() if (shapes is not None and prewarm) else None

    rec = Recorder(progress, _n_tasks(cfg, shapes is not None))
    jit = 0.0
    import numba

    threads_before = numba.get_num_threads()
    # Timings are single-threaded: on a shared 2-core machine a parallel (prange) kernel waits
    # for a descheduled thread and small problems get several times slower, at random.
    numba.set_num_threads(max(1, min(cfg.threads, threads_before)))
    extra["numba_threads"] = numba.get_num_threads()
    try:
        run_sph(cfg, rec)
        logger.info("SPH part done: %d rows", len(rec.rows))
        plots = plots_sph(rec.rows, cfg, out)
        logger.info("SPH plots done")
        if shapes is not None:
            t0 = time.perf_counter()
            warm_up_2d_linear(shapes, cfg)
            wait_prewarm(proc)
            warm_up(shapes, cfg)
            jit = time.perf_counter() - t0
            logger.info("JIT warm-up (after the SPH part) %.1f s", jit)
            run_mls_1d(cfg, rec, shapes)
            logger.info("1D shape functions done: %d rows", len(rec.rows))
            run_mls_2d(cfg, rec, shapes)
            logger.info("2D shape functions done: %d rows", len(rec.rows))
    finally:
        numba.set_num_threads(threads_before)
        rec.close()
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()
    extra["jit_warmup_s"] = round(jit, 2)
    rows = rec.rows
    t_measure = time.perf_counter() - t_start

    fits = compute_fits(rows)
    res = analyse(rows, fits, cfg)
    res["part2_skipped"] = shapes is None
    res["findings"] = findings(res, cfg)
    if rec.notes:
        res["findings"].append(
            "Rank check (a point needs at least as many neighbours as basis terms for order ≥ 1): "
            + "; ".join(rec.notes)
            + ". Such a moment matrix is singular, so the point should "
            "have fallen back to a lower order; its shape-function gradient is not trustworthy."
        )
        for note in rec.notes:
            logger.warning("shape functions: %s", note)

    csv_path = out / "kernel_study.csv"
    fits_path = out / "kernel_study_fits.csv"
    summary_path = out / "summary.md"
    prov_path = out / "provenance.json"
    write_csv_rows(csv_path, COLUMNS, csv_cells(rows, COLUMNS))
    write_csv_rows(fits_path, FIT_COLUMNS, csv_cells(fits, FIT_COLUMNS))
    logger.info("tables written")
    plots += plots_shape_functions(rows, cfg, out)
    logger.info("plots done")
    wall = time.perf_counter() - t_start
    extra.update(
        wall_s=round(wall, 2),
        measure_s=round(t_measure, 2),
        n_rows=len(rows),
        call=dict(out=str(out), quick=quick, progress=progress),
    )
    prov = provenance(cfg, extra)
    files = {
        "csv": csv_path.name,
        "fits": fits_path.name,
        "provenance": prov_path.name,
        **{p.stem: p.name for p in plots},
    }
    atomic_write(summary_path, summary_text(res, cfg, prov, files))
    atomic_write(prov_path, json.dumps(prov, indent=2) + "\n")
    headline = {
        "beta_integral": {
            k: {f: res["beta_integral"][k][f] for f in SMOOTH_FUNCTIONS} for k in cfg.sph_kernels
        },
        "worst_rel_5nb": res["worst_rel_5nb"],
        "orders_2d": res.get("orders_2d", {}),
        "part2_skipped": shapes is None,
    }
    logger.info("kernel study finished in %.1f s", wall)
    return KernelStudyResult(
        out=out,
        quick=quick,
        csv_path=csv_path,
        fits_path=fits_path,
        summary_path=summary_path,
        provenance_path=prov_path,
        plots=plots,
        rows=rows,
        fits=fits,
        headline=headline,
        wall_s=wall,
    )
