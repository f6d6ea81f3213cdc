r"""The study's three sweeps, their configuration, and the observed orders.

``patch``
    Linear patch tests (:func:`~.problems.poisson_patch`, :func:`~.problems.elastic_patch`) on
    regular and perturbed 9 x 9 nodes, for every rule, with Nitsche and penalty conditions.
``convergence``
    :func:`~.problems.poisson_mms` and :func:`~.problems.timoshenko` over four refinements
    (three with ``quick``), rule x basis x kernel at a fixed support radius per basis
    (:data:`SUPPORT_RATIO`), on regular nodes, plus perturbed nodes for the kernels of
    ``GalerkinConfig.perturbed_kernels``.
``h_sweep``
    Support radius over spacing from 1.5 to 4 at a fixed, small resolution: the error with
    boundary conditions and the zero-energy modes of the stiffness without them
    (:func:`~.runner.spectrum`), plus the measured Nitsche inverse constant.

Support radius
--------------
Kernels are compared at **equal support radius** ``κh`` (``κ`` = 2 for the cubic spline and
Wendland C2, 3 for the quintic spline): ``support_ratio = κh/Δx`` is 3 for linear bases and
4 for quadratic bases, i.e. dilations ``h/Δx`` of 1.5 / 2.0 (cubic spline, Wendland C2) and
1.0 / 1.33 (quintic spline). A quadratic MLS basis needs six independent neighbours at every
point, including the domain corners, where a support radius of 3Δx holds only a quarter disc of
nodes; 4Δx leaves a margin (no fallback to a lower order anywhere in the study, see the
``n_fallback`` column). The h-sweep shows what happens at other radii.

>>> fit = observed_order([0.4, 0.2, 0.1], [1.6e-2, 4e-3, 1e-3])
>>> round(fit[0], 6), round(fit[1], 6)
(2.0, 2.0)
"""

from __future__ import annotations

import logging
import math
from collections import defaultdict
from dataclasses import dataclass, field
from typing import Callable, Iterable

import numpy as np

from mlsgalerkin.studies.galerkin.runner import SolveSpec, measure, spectrum

__all__ = [
    "GalerkinConfig",
    "make_config",
    "patch_specs",
    "convergence_specs",
    "sweep_specs",
    "warm_up_specs",
    "run_sweep",
    "observed_order",
    "fit_orders",
    "SUPPORT_RATIO",
    "ROUNDOFF",
]

logger = logging.getLogger(__name__)

#: Support radius over spacing (κh/Δx) of the convergence study, per polynomial basis.
SUPPORT_RATIO = {"linear": 3.0, "quadratic": 4.0}
#: Relative errors below this are round-off and are not fitted.
ROUNDOFF = 1e-12


@dataclass(frozen=True)
class GalerkinConfig:
    """All sweep parameters (see :func:`make_config`)."""

    quick: bool
    rules: tuple[str, ...]
    bases: tuple[str, ...]
    kernels: tuple[str, ...]
    # patch tests
    patch_problems: tuple[str, ...]
    patch_spacing: float
    patch_kernels: tuple[str, ...]
    patch_bases: tuple[str, ...]
    penalty_kernels: tuple[str, ...]
    # convergence
    levels: dict = field(hash=False)
    perturbed_kernels: tuple[str, ...] = ()
    #: rules measured only with a linear basis and the first kernel, on regular nodes
    ablation_rules: tuple[str, ...] = ()
    # smoothing-length sweep
    sweep_spacing: dict = field(default_factory=dict, hash=False)
    sweep_ratios: tuple[float, ...] = ()
    sweep_kernels: tuple[str, ...] = ()
    sweep_layouts: tuple[str, ...] = ("regular",)
    sweep_perturbed_kernels: tuple[str, ...] = ()
    eig_tol: float = 1e-10
    # timing and reproducibility
    seed: int = 20240611
    min_time: float = 0.3
    max_repeats: int = 3
    threads: int = 1

    @property
    def support_ratio(self) -> dict[str, float]:
        return dict(SUPPORT_RATIO)


def make_config(quick: bool = False) -> GalerkinConfig:
    """Default (about 8 minutes on 2 cores) or ``quick`` (three levels, well under a minute)."""
    kernels = ("cubic_spline", "quintic_spline", "wendland_c2")
    rules = ("dni", "scni", "vci")
    common = dict(
        rules=rules,
        bases=("linear", "quadratic"),
        patch_problems=("poisson_patch", "elastic_patch"),
        patch_spacing=1.0 / 8.0,
        eig_tol=1e-10,
    )
    if quick:
        return GalerkinConfig(
            quick=True,
            kernels=("cubic_spline",),
            patch_kernels=("cubic_spline",),
            patch_bases=("linear",),
            penalty_kernels=("cubic_spline",),
            levels={"poisson_mms": (1 / 8, 1 / 16, 1 / 32), "timoshenko": (4.0, 2.0, 1.0)},
            perturbed_kernels=(),
            sweep_spacing={"poisson_mms": 1 / 12, "timoshenko": 3.0},
            sweep_ratios=(2.0, 3.0, 4.0),
            sweep_kernels=("cubic_spline",),
            sweep_layouts=("regular",),
            min_time=0.0,
            max_repeats=1,
            **common,
        )
    return GalerkinConfig(
        quick=False,
        kernels=kernels,
        patch_kernels=kernels,
        patch_bases=("linear", "quadratic"),
        penalty_kernels=("cubic_spline",),
        levels={"poisson_mms": (1 / 8, 1 / 16, 1 / 32, 1 / 64),
                "timoshenko": (4.0, 2.0, 1.0, 0.5)},
        perturbed_kernels=("cubic_spline",),
        ablation_rules=("vci_constant",),
        sweep_spacing={"poisson_mms": 1 / 16, "timoshenko": 2.0},
        sweep_ratios=(1.5, 2.0, 2.5, 3.0, 3.5, 4.0),
        sweep_kernels=kernels,
        sweep_layouts=("regular", "perturbed"),
        sweep_perturbed_kernels=("cubic_spline",),
        **common,
    )


# --------------------------------------------------------------------------------------
# the points of each sweep
# --------------------------------------------------------------------------------------


def patch_specs(cfg: GalerkinConfig) -> list[SolveSpec]:
    """Patch tests: Nitsche for every kernel/basis, penalty for ``penalty_kernels`` (linear)."""
    out = []
    for problem in cfg.patch_problems:
        for rule in cfg.rules:
            for nodes in ("regular", "perturbed"):
                for basis in cfg.patch_bases:
                    for kernel in cfg.patch_kernels:
                        out.append(SolveSpec(problem, rule, basis, kernel, SUPPORT_RATIO[basis],
                                             cfg.patch_spacing, nodes, "nitsche", cfg.seed))
                for kernel in cfg.penalty_kernels:
                    out.append(SolveSpec(problem, rule, "linear", kernel, SUPPORT_RATIO["linear"],
                                         cfg.patch_spacing, nodes, "penalty", cfg.seed))
    return out


def convergence_specs(cfg: GalerkinConfig) -> list[SolveSpec]:
    """Refinement levels of every problem, coarse to fine within each series."""
    out = []
    for problem, spacings in cfg.levels.items():
        for nodes in ("regular", "perturbed"):
            kernels = cfg.kernels if nodes == "regular" else cfg.perturbed_kernels
            for rule in cfg.rules:
                for basis in cfg.bases:
                    for kernel in kernels:
                        for s in sorted(spacings, reverse=True):
                            out.append(SolveSpec(problem, rule, basis, kernel,
                                                 SUPPORT_RATIO[basis], s, nodes, "nitsche",
                                                 cfg.seed))
        for rule in cfg.ablation_rules:
            for s in sorted(spacings, reverse=True):
                out.append(SolveSpec(problem, rule, "linear", cfg.kernels[0],
                                     SUPPORT_RATIO["linear"], s, "regular", "nitsche", cfg.seed))
    return out


def sweep_specs(cfg: GalerkinConfig) -> list[SolveSpec]:
    """Support-radius sweep at the fixed spacing of each problem."""
    out = []
    for problem, s in cfg.sweep_spacing.items():
        for nodes in cfg.sweep_layouts:
            kernels = cfg.sweep_kernels if nodes == "regular" else cfg.sweep_perturbed_kernels
            for rule in cfg.rules:
                for basis in cfg.bases:
                    for kernel in kernels:
                        for r in cfg.sweep_ratios:
                            out.append(SolveSpec(problem, rule, basis, kernel, r, s, nodes,
                                                 "nitsche", cfg.seed))
    return out


def warm_up_specs(cfg: GalerkinConfig) -> list[SolveSpec]:
    """One coarse solve per (problem, rule, basis): loads the numba kernels before timing."""
    out = []
    for problem, spacings in cfg.levels.items():
        for rule in cfg.rules:
            for basis in cfg.bases:
                out.append(SolveSpec(problem, rule, basis, cfg.kernels[0], SUPPORT_RATIO[basis],
                                     max(spacings), "regular", "nitsche", cfg.seed))
    return out


def run_sweep(study: str, specs: Iterable[SolveSpec], cfg: GalerkinConfig,
              tick: Callable[[], None] | None = None, *, with_spectrum: bool = False,
              timed: bool = True) -> tuple[list[dict], dict]:
    """Measure every spec; returns the rows (``study`` column set) and, with ``with_spectrum``,
    the normalised stiffness spectra keyed by spec."""
    rows, spectra = [], {}
    for spec in specs:
        if timed:
            row = measure(spec, min_time=cfg.min_time, max_repeats=cfg.max_repeats)
        else:
            row = measure(spec, min_time=0.0, max_repeats=1)
        if with_spectrum:
            srow, vals = spectrum(spec, tol=cfg.eig_tol)
            for k in ("n_rigid", "n_zero_modes", "n_spurious_modes", "eig_below", "eig_above",
                      "eig_gap", "eig_first", "energy_ratio_max", "n_soft_modes", "nitsche_ci",
                      "eig_tol", "spectrum"):
                row[k] = srow[k]
            spectra[spec] = vals
        row = {"study": study, **row}
        rows.append(row)
        logger.debug("%s %s %s %s %s r=%g dx=%g: L2 %.3g, H1 %.3g, %.3f s", study, spec.problem,
                     spec.rule, spec.basis, spec.kernel, spec.support_ratio, spec.spacing,
                     row["error_l2"], row["error_h1"], row["wall_s"])
        if tick is not None:
            tick()
    return rows, spectra


# --------------------------------------------------------------------------------------
# observed orders
# --------------------------------------------------------------------------------------


def observed_order(spacings: Iterable[float], errors: Iterable[float],
                   floor: float = ROUNDOFF) -> tuple[float, float]:
    """Least-squares slope of ``log error`` against ``log spacing`` over all levels, and the
    slope between the two finest levels. NaN when fewer than two usable levels remain (errors
    at or below ``floor`` or not finite are dropped)."""
    h = np.asarray(list(spacings), float)
    e = np.asarray(list(errors), float)
    keep = np.isfinite(h) & np.isfinite(e) & (h > 0) & (e > floor)
    h, e = h[keep], e[keep]
    if h.size < 2 or np.unique(h).size < 2:
        return math.nan, math.nan
    order = np.argsort(h)
    h, e = h[order], e[order]
    fit = float(np.polyfit(np.log(h), np.log(e), 1)[0])
    last = float(np.log(e[1] / e[0]) / np.log(h[1] / h[0]))
    return round(fit, 12), round(last, 12)


ORDER_QUANTITIES = ("error_l2", "error_h1", "error_energy", "error_h1_rule")


def fit_orders(rows: list[dict]) -> list[dict]:
    """Observed orders per convergence series (problem, rule, basis, kernel, nodes)."""
    series: dict[tuple, list[dict]] = defaultdict(list)
    for r in rows:
        if r["study"] == "convergence":
            series[(r["problem"], r["rule"], r["basis"], r["kernel"], r["nodes"])].append(r)
    out = []
    for (problem, rule, basis, kernel, nodes), rs in series.items():
        rs = sorted(rs, key=lambda r: -r["spacing"])
        spacings = [r["spacing"] for r in rs]
        fin = rs[-1]
        row = dict(problem=problem, rule=rule, basis=basis, kernel=kernel, nodes=nodes,
                   support_ratio=fin["support_ratio"], n_levels=len(rs),
                   spacing_min=fin["spacing"], spacing_max=rs[0]["spacing"],
                   n_nodes_max=fin["n_nodes"], wall_s_finest=fin["wall_s"])
        for q in ORDER_QUANTITIES:
            fit, last = observed_order(spacings, [r[q] for r in rs])
            key = q.removeprefix("error_")
            row[f"order_{key}"] = fit
            row[f"order_{key}_last"] = last
            row[f"{q}_finest"] = fin[q]
            row[f"{q}_max"] = max(r[q] for r in rs)
        out.append(row)
    return out
