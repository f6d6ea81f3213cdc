r"""The study's three sweeps: configuration, grid points, the measurement of one point, orders.

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

Grid points
-----------
:func:`study_points` turns the specs of the three sweeps into the study engine's grid points
(the fields of :class:`~.runner.SolveSpec` plus ``study``); :func:`measure_solve` measures one
(untimed repeats for the patch tests; the stiffness spectrum for the h-sweep) and
:func:`warm_up` loads the numba kernels in each worker before any timing.

>>> cfg = make_config(quick=True)
>>> len(study_points(cfg)), study_points(cfg)[0]["study"]
(96, 'patch')
"""

from __future__ import annotations

import logging
from collections import defaultdict
from dataclasses import asdict, dataclass, field
from typing import Any

from mlsgalerkin.analysis.convergence import observed_order
from mlsgalerkin.studies.galerkin.runner import SolveSpec, measure, spectrum

__all__ = [
    "GalerkinConfig",
    "make_config",
    "patch_specs",
    "convergence_specs",
    "sweep_specs",
    "warm_up_specs",
    "study_points",
    "measure_solve",
    "warm_up",
    "energy_quantity",
    "fit_orders",
    "ORDER_QUANTITIES",
    "SPECTRUM_COLUMNS",
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


def study_points(cfg: GalerkinConfig) -> list[dict[str, Any]]:
    """Grid points of the whole study: patch tests, convergence, h-sweep (in this order)."""
    return [{"study": study, **asdict(spec)}
            for study, specs in (("patch", patch_specs(cfg)),
                                 ("convergence", convergence_specs(cfg)),
                                 ("h_sweep", sweep_specs(cfg)))
            for spec in specs]


#: Columns of the h-sweep rows that come from :func:`~.runner.spectrum`.
SPECTRUM_COLUMNS = ("n_rigid", "n_zero_modes", "n_spurious_modes", "eig_below", "eig_above",
                    "eig_gap", "eig_first", "energy_ratio_max", "n_soft_modes", "nitsche_ci",
                    "eig_tol", "spectrum")


def measure_solve(cfg: GalerkinConfig, study: str, problem: str, rule: str, basis: str,
                  kernel: str, support_ratio: float, spacing: float, nodes: str, bc: str,
                  seed: int) -> dict[str, Any]:
    """The CSV row of one grid point of :func:`study_points` (a :class:`~.runner.SolveSpec`
    and the sweep it belongs to).

    Patch tests are solved once; convergence and h-sweep points are timed with the repeat
    policy of ``cfg`` (``min_time``, ``max_repeats``); h-sweep points add the
    :data:`SPECTRUM_COLUMNS` and ``eigenvalues`` (the normalised stiffness spectrum, ascending;
    not a CSV column).
    """
    spec = SolveSpec(problem, rule, basis, kernel, support_ratio, spacing, nodes, bc, seed)
    if study == "patch":
        row = measure(spec, min_time=0.0, max_repeats=1)
    else:
        row = measure(spec, min_time=cfg.min_time, max_repeats=cfg.max_repeats)
    if study == "h_sweep":
        srow, vals = spectrum(spec, tol=cfg.eig_tol)
        row.update({k: srow[k] for k in SPECTRUM_COLUMNS}, eigenvalues=vals)
    logger.debug("%s %s %s %s %s r=%g dx=%g: L2 %.3g, H1 %.3g, %.3f s", study, spec.problem,
                 spec.rule, spec.basis, spec.kernel, spec.support_ratio, spec.spacing,
                 row["error_l2"], row["error_h1"], row["wall_s"])
    return row


def warm_up(specs: tuple[SolveSpec, ...]) -> None:
    """Solve ``specs`` once, untimed (loads the numba kernels before any measurement)."""
    for spec in specs:
        measure(spec, min_time=0.0, max_repeats=1)


# --------------------------------------------------------------------------------------
# observed orders
# --------------------------------------------------------------------------------------


def energy_quantity(problem: str) -> tuple[str, str]:
    """The column and name of ``problem``'s energy-type error: the energy norm for the
    Timoshenko beam, the H1 seminorm (the energy norm of Poisson) otherwise."""
    return ("error_energy", "energy") if problem == "timoshenko" else ("error_h1", "H1")


ORDER_QUANTITIES = ("error_l2", "error_h1", "error_energy", "error_h1_rule")


def fit_orders(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Observed orders per convergence series (problem, rule, basis, kernel, nodes):
    :func:`~mlsgalerkin.analysis.convergence.observed_order` of every error of
    :data:`ORDER_QUANTITIES` against the spacing, and the errors at the finest level."""
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
            fit, last = observed_order(spacings, [r[q] for r in rs], floor=ROUNDOFF)
            key = q.removeprefix("error_")
            row[f"order_{key}"] = fit
            row[f"order_{key}_last"] = last
            row[f"{q}_finest"] = fin[q]
            row[f"{q}_max"] = max(r[q] for r in rs)
        out.append(row)
    return out
