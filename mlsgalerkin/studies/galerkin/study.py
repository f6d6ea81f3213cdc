"""Run the whole Galerkin study and write its files (CSV, figures, summary, provenance)."""

from __future__ import annotations

import logging
import time
from pathlib import Path

from mlsgalerkin.studies.galerkin.output import atomic_write, csv_text, provenance, write_json
from mlsgalerkin.studies.galerkin.plots import make_plots
from mlsgalerkin.studies.galerkin.report import GalerkinStudyResult, summary_markdown
from mlsgalerkin.studies.galerkin.sweeps import (
    convergence_specs,
    fit_orders,
    make_config,
    patch_specs,
    run_sweep,
    sweep_specs,
    warm_up_specs,
)

__all__ = ["run_galerkin_study", "COLUMNS", "ORDER_COLUMNS"]

logger = logging.getLogger(__name__)

COLUMNS = [
    "study", "problem", "rule", "basis", "kernel", "support_ratio", "dilation", "spacing",
    "n_nodes", "n_dofs", "nodes", "bc", "error_l2", "error_h1", "error_energy", "error_h1_rule",
    "wall_s",
    "wall_shape_s", "wall_assembly_s", "wall_solve_s", "wall_error_s", "neighbors_mean",
    "n_fallback", "finite", "n_rigid", "n_zero_modes", "n_spurious_modes", "eig_below",
    "eig_above", "eig_gap", "eig_first", "eig_tol", "spectrum", "energy_ratio_max",
    "n_soft_modes", "nitsche_ci",
]
ORDER_COLUMNS = [
    "problem", "rule", "basis", "kernel", "nodes", "support_ratio", "n_levels", "spacing_max",
    "spacing_min", "n_nodes_max", "order_l2", "order_l2_last", "order_h1", "order_h1_last",
    "order_energy", "order_energy_last", "order_h1_rule", "order_h1_rule_last",
    "error_l2_finest", "error_h1_finest",
    "error_energy_finest", "error_h1_rule_finest", "wall_s_finest",
]


class _Progress:
    def __init__(self, enabled: bool, total: int) -> None:
        self.bar = None
        if enabled:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=total, desc="galerkin study", unit="solve", leave=False)

    def set(self, stage: str) -> None:
        if self.bar is not None:
            self.bar.set_postfix_str(stage)

    def tick(self) -> None:
        if self.bar is not None:
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run_galerkin_study(out: str | Path, quick: bool = False,
                       progress: bool = True) -> GalerkinStudyResult:
    """Patch tests, convergence orders, smoothing-length sweep and work-precision data.

    Parameters
    ----------
    out : output directory (created if needed).
    quick : three refinement levels, one kernel, a short sweep (well under a minute).
    progress : show a tqdm progress bar.

    Writes ``galerkin_convergence.csv`` (one row per solve), ``galerkin_orders.csv`` (observed
    orders per series), PNG figures, ``summary.md`` and ``provenance.json``.
    """
    import numba

    t_start = time.perf_counter()
    cfg = make_config(quick)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    patch, conv, sweep = patch_specs(cfg), convergence_specs(cfg), sweep_specs(cfg)
    warm = warm_up_specs(cfg)
    bar = _Progress(progress, len(warm) + len(patch) + len(conv) + len(sweep))
    threads_before = numba.get_num_threads()
    # Timings are single-threaded: on a shared 2-core machine a parallel (prange) kernel waits
    # for a descheduled thread and small problems get slower at random.
    numba.set_num_threads(max(1, min(cfg.threads, threads_before)))
    threads = numba.get_num_threads()
    stages = {}
    try:
        t0 = time.perf_counter()
        bar.set("warm-up")
        run_sweep("warm_up", warm, cfg, bar.tick, timed=False)
        stages["warm_up_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        bar.set("patch tests")
        rows, _ = run_sweep("patch", patch, cfg, bar.tick, timed=False)
        stages["patch_s"] = time.perf_counter() - t0
        logger.info("patch tests: %d solves in %.1f s", len(patch), stages["patch_s"])
        t0 = time.perf_counter()
        bar.set("convergence")
        r, _ = run_sweep("convergence", conv, cfg, bar.tick)
        rows += r
        stages["convergence_s"] = time.perf_counter() - t0
        logger.info("convergence: %d solves in %.1f s", len(conv), stages["convergence_s"])
        t0 = time.perf_counter()
        bar.set("h-sweep")
        r, spectra = run_sweep("h_sweep", sweep, cfg, bar.tick, with_spectrum=True)
        rows += r
        stages["h_sweep_s"] = time.perf_counter() - t0
        logger.info("h-sweep: %d solves + spectra in %.1f s", len(sweep), stages["h_sweep_s"])
    finally:
        numba.set_num_threads(threads_before)
        bar.close()

    orders = fit_orders(rows)
    csv_path = atomic_write(out / "galerkin_convergence.csv", csv_text(rows, COLUMNS))
    orders_path = atomic_write(out / "galerkin_orders.csv", csv_text(orders, ORDER_COLUMNS))
    t0 = time.perf_counter()
    plots = make_plots(rows, spectra, cfg, out)
    stages["plots_s"] = time.perf_counter() - t0
    wall = time.perf_counter() - t_start
    prov = provenance("galerkin_convergence", quick, {
        "wall_s": round(wall, 1),
        "stages_s": {k: round(v, 1) for k, v in stages.items()},
        "numba_threads": threads,
        "n_solves": len(rows),
        "seed": cfg.seed,
        "call": {"out": str(out), "quick": quick, "progress": progress},
    })
    prov_path = out / "provenance.json"
    files = {"csv": csv_path.name, "orders": orders_path.name, "provenance": prov_path.name,
             **{p.stem: p.name for p in plots}, "summary": "summary.md"}
    summary_path = atomic_write(out / "summary.md",
                                summary_markdown(rows, orders, cfg, prov, files))
    write_json(prov_path, prov)
    logger.info("Galerkin study finished in %.1f s", wall)
    return GalerkinStudyResult(out=out, quick=quick, csv_path=csv_path, orders_path=orders_path,
                               summary_path=summary_path, provenance_path=prov_path, plots=plots,
                               rows=rows, orders=orders, wall_s=wall)
