"""Part 2 of the kernel study: MLS, RKPM and Shepard shape functions in 1D and 2D.

:func:`build_shapes` maps the study's method names (:data:`~.config.METHOD_SPECS`) onto
:func:`mlsgalerkin.shape_functions`; :func:`mls_points` lists the grid points of the 1D and 2D
sweeps and :func:`measure_mls_1d` / :func:`measure_mls_2d` measure one point. :func:`warm_up`
calls every numba path on tiny inputs; the study engine runs it once per worker process before
any timing, so no wall time includes compilation.
"""

from __future__ import annotations

import logging
import warnings
from typing import Any

import numpy as np

from mlsgalerkin import shape_functions
from mlsgalerkin.approximation import ShapeTable
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.neighbors import NeighborTable
from mlsgalerkin.studies.engine.timing import best_time
from mlsgalerkin.studies.kernels.config import (
    DOMAIN_1D,
    FUNCTIONS_BY_LABEL,
    METHOD_SPECS,
    U2D_LABEL,
    StudyConfig,
    grad_u2d,
    u2d,
)
from mlsgalerkin.studies.kernels.layouts import jittered_particles_1d, local_spacing, nodes_2d
from mlsgalerkin.studies.kernels.measure import interior_mask, region_rows
from mlsgalerkin.studies.kernels.sph import neighbors_1d

__all__ = [
    "build_shapes",
    "measure_mls_1d",
    "measure_mls_2d",
    "mls_points",
    "warm_up",
]

logger = logging.getLogger(__name__)

#: Basis terms of a full-rank moment matrix of order 0, 1, 2 in 2D.
_TERMS_2D = np.array([1, 3, 6])


def build_shapes(
    points: np.ndarray,
    nodes: np.ndarray,
    h: float,
    kernel: str,
    method: str,
    volumes: np.ndarray | None = None,
    neighbors: NeighborTable | None = None,
) -> ShapeTable:
    """Shape functions of study method ``method`` (a :data:`METHOD_SPECS` key) at ``points``.

    Fallbacks to a lower order are counted by the table (``n_fallback``), not warned about.
    """
    meth, basis, needs_volumes = METHOD_SPECS[method]
    kw: dict[str, Any] = dict(kernel=kernel, basis=basis, method=meth, on_fallback="ignore")
    if needs_volumes:
        kw["volumes"] = volumes
    if neighbors is not None:
        kw["neighbors"] = neighbors
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return shape_functions(points, nodes, h, **kw)


def warm_up(cfg: StudyConfig) -> None:
    """Call every numba path of part 2 once on tiny inputs (compiles or loads the cache)."""
    x1 = np.linspace(0.0, 1.0, 12)
    g = np.linspace(0.0, 1.0, 6)
    x2 = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
    nb1 = neighbors_1d(x1, x1, 0.5)
    for m in cfg.mls_methods:
        t = build_shapes(x1, x1, 0.25, "cubic_spline", m, volumes=local_spacing(x1), neighbors=nb1)
        t.interpolate(x1)
    for kname in cfg.kernels_2d:
        for m in cfg.methods_2d:
            t = build_shapes(x2, x2, 0.4, kname, m)
            t.interpolate(x2[:, 0])
            t.gradient(x2[:, 0])


# --------------------------------------------------------------------------------------
# the points of the 1D and 2D sweeps
# --------------------------------------------------------------------------------------


def mls_points(cfg: StudyConfig) -> list[dict[str, Any]]:
    """Grid points of part 2: 1D sweeps (h, N, refinement at fixed h/Δx) per kernel and method,
    then 2D sweeps (h/Δx, resolution) per kernel, layout and method."""
    points: list[dict[str, Any]] = []
    for kernel in cfg.mls_kernels:
        for method in cfg.mls_methods:
            base = dict(part="mls1d", approximation=method, kernel=kernel)
            points += [dict(base, sweep="h", h=h, n_particles=cfg.part_n_fixed)
                       for h in cfg.part_h]
            points += [dict(base, sweep="n_particles", h=cfg.part_h_fixed, n_particles=n)
                       for n in cfg.mls_part_n]
            points += [dict(base, sweep="refine", n_particles=n) for n in cfg.refine_n]
    for kernel in cfg.kernels_2d:
        for layout in cfg.layouts_2d:
            for method in cfg.methods_2d:
                base = dict(part="mls2d", approximation=method, layout=layout, kernel=kernel)
                points += [dict(base, sweep="h_over_dx", h_over_dx=r, n_side=cfg.n_fixed_2d)
                           for r in cfg.ratios_2d]
                points += [dict(base, sweep="resolution", h_over_dx=cfg.ratio_fixed_2d, n_side=n)
                           for n in cfg.levels_2d]
    return points


def measure_mls_1d(cfg: StudyConfig, approximation: str, kernel: str, sweep: str,
                   n_particles: int, h: float | None = None) -> list[dict[str, Any]]:
    """Rows of one 1D point: ``n_particles`` jittered particles on [0, 2], evaluated at the
    particles; ``h`` defaults to ``cfg.refine_ratio`` times the mean spacing (refinement).
    ``wall_s`` is the best time of building the shape functions (with the neighbour search)
    plus applying them to one function."""
    lo, hi = DOMAIN_1D
    k = get_kernel(kernel)
    funcs = [FUNCTIONS_BY_LABEL[f] for f in cfg.mls_functions]
    n = n_particles
    dx = (hi - lo) / (n - 1)
    if h is None:
        h = cfg.refine_ratio * dx
    x = jittered_particles_1d(n, cfg.jitter_1d, cfg.seed)
    vol = local_spacing(x)
    masks = {
        "interior": interior_mask(x, k.support * h, lo, hi),
        "all": np.ones(x.shape, bool),
    }
    table, t_build = best_time(
        lambda: build_shapes(x, x, h, kernel, approximation, volumes=vol,
                             neighbors=neighbors_1d(x, x, k.support * h)),
        cfg.min_time,
        cfg.repeats,
    )
    rows = []
    for fn in funcs:
        fx = fn.f(x)
        approx, t = best_time(lambda: table.interpolate(fn.f(x)), cfg.min_time, cfg.repeats)
        base = dict(
            part="mls1d",
            approximation=approximation,
            layout="jittered",
            kernel=kernel,
            function=fn.label,
            sweep=sweep,
            h=h,
            h_over_dx=h / dx,
            n_particles=n,
            spacing=dx,
            n_fallback=int(table.n_fallback),
        )
        rows += region_rows(base, masks, approx, fx, wall_s=t_build + t,
                            counts=np.diff(table.indptr))
    return rows


def _rank_note(table: ShapeTable, pts: np.ndarray, grad: np.ndarray, g_ex: np.ndarray,
               what: str) -> str | None:
    """A point accepted at order p with fewer neighbours than basis terms (its moment matrix is
    singular, so it should have fallen back): a sentence, or None."""
    order = getattr(table, "order", None)
    if order is None:
        return None
    counts = np.diff(table.indptr)
    bad = np.flatnonzero(counts < _TERMS_2D[np.clip(order.astype(int), 0, 2)])
    if not bad.size:
        return None
    j = int(bad[0])
    return (f"{what}: {bad.size} point(s) accepted at order {int(order[j])} with fewer "
            f"neighbours than basis terms, e.g. ({pts[j, 0]:.4g}, {pts[j, 1]:.4g}) with "
            f"{int(counts[j])} neighbour(s), condition {float(table.condition[j]):.3g}, "
            f"gradient error {float(np.linalg.norm(grad[j] - g_ex[j])):.3g}")


def measure_mls_2d(cfg: StudyConfig, approximation: str, layout: str, kernel: str, sweep: str,
                   h_over_dx: float, n_side: int) -> list[dict[str, Any]]:
    """Rows of one 2D point: value and gradient errors of :func:`~.config.u2d` from
    ``n_side**2`` nodes at ``h = h_over_dx Δx``, on an evaluation grid of spacing
    ``Δx / cfg.eval_per_dx_2d``; ``wall_s`` is the best time of building the shape functions and
    applying them (value and gradient). A point that cannot be built (e.g. an evaluation point
    without neighbours) is logged and gives no rows. ``rank_note`` (not a CSV column) describes
    points accepted with a singular moment matrix."""
    k = get_kernel(kernel)
    n = n_side
    ge = np.linspace(0.0, 1.0, cfg.eval_per_dx_2d * (n - 1) + 1)
    pts = np.stack(np.meshgrid(ge, ge, indexing="ij"), axis=-1).reshape(-1, 2)
    u_ex, g_ex = u2d(pts), grad_u2d(pts)
    nodes = nodes_2d(layout, n, cfg.jitter_2d, cfg.seed)
    dx = 1.0 / (n - 1)
    h = h_over_dx * dx
    masks = {
        "interior": interior_mask(pts, k.support * h),
        "all": np.ones(pts.shape[0], bool),
    }
    un = u2d(nodes)

    def work():
        tab = build_shapes(pts, nodes, h, kernel, approximation)
        return tab, tab.interpolate(un), tab.gradient(un)

    try:
        (table, approx, grad), t = best_time(work, cfg.min_time, cfg.repeats)
    except ValueError as exc:  # e.g. an evaluation point without neighbours
        logger.warning("2D %s %s %s n=%d h/dx=%.2f failed: %s", layout, approximation, kernel,
                       n, h_over_dx, exc)
        return []
    base = dict(
        part="mls2d",
        approximation=approximation,
        layout=layout,
        kernel=kernel,
        function=U2D_LABEL,
        sweep=sweep,
        h=h,
        h_over_dx=h_over_dx,
        n_particles=int(nodes.shape[0]),
        spacing=dx,
        n_fallback=int(table.n_fallback),
        rank_note=_rank_note(table, pts, grad, g_ex, f"{layout} {approximation} {kernel}, "
                             f"n = {n}² nodes, h/Δx = {h_over_dx:g}"),
    )
    return region_rows(base, masks, approx, u_ex, wall_s=t, counts=np.diff(table.indptr),
                       grad=grad, grad_exact=g_ex, cond=getattr(table, "condition", None))
