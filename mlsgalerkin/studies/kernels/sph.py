r"""Part 1 of the kernel study: SPH integral and particle approximations in 1D, and their sweep.

*Integral approximation* :math:`\langle F(x_a)\rangle = \sum_b F(x_b) W(x_a - x_b, h)\,
\delta x'` with the midpoint rule on the support; *particle approximation*
:math:`\langle F(x_a)\rangle = \sum_b F(x_b) W_{ab} / \sum_b W_{ab}` (Shepard-normalised) on
equally spaced particles. Both are vectorised numpy (no compiled code).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from mlsgalerkin.kernels import Kernel, get_kernel
from mlsgalerkin.neighbors import NeighborTable
from mlsgalerkin.studies.engine.timing import best_time
from mlsgalerkin.studies.kernels.config import DOMAIN_1D, FUNCTIONS, StudyConfig
from mlsgalerkin.studies.kernels.measure import interior_mask, region_rows

__all__ = [
    "ParticleSum",
    "integral_approximation",
    "measure_integral",
    "measure_particle",
    "neighbors_1d",
    "particle_approximation",
    "particle_sum",
    "quadrature_offsets",
    "sph_points",
]


def quadrature_offsets(kernel: Kernel, h: float, n_neighbors: int) -> tuple[np.ndarray, np.ndarray]:
    """Offsets ``s_b`` and weights ``W(s_b, h) δx'`` of the midpoint rule on the support."""
    dxq = 2.0 * kernel.support * h / n_neighbors
    s = (np.arange(n_neighbors) - 0.5 * (n_neighbors - 1)) * dxq
    return s, kernel.value(np.abs(s), h, 1) * dxq


def integral_approximation(
    f: Callable[[np.ndarray], np.ndarray],
    x_eval: np.ndarray,
    kernel: str | Kernel,
    h: float,
    n_neighbors: int,
) -> np.ndarray:
    r"""``<F(x_a)> = Σ_b F(x_a + s_b) W(s_b, h) δx'`` with the midpoint rule on the support.

    ``δx' = 2 κ h / n_neighbors``; all ``n_neighbors`` quadrature points lie inside the support
    and symmetric about ``x_a``; they may lie outside the domain (``f`` is evaluated there).
    """
    k = get_kernel(kernel)
    s, w = quadrature_offsets(k, h, n_neighbors)
    return f(np.asarray(x_eval, float)[:, None] + s[None, :]) @ w


@dataclass(frozen=True)
class ParticleSum:
    """CSR weights of the normalised particle sum; ``apply(F)`` evaluates it."""

    rows: np.ndarray
    cols: np.ndarray
    w: np.ndarray
    den: np.ndarray
    counts: np.ndarray

    def apply(self, values: np.ndarray) -> np.ndarray:
        """The normalised sum of the particle ``values`` at every particle."""
        n = self.den.shape[0]
        return np.bincount(self.rows, self.w * values[self.cols], minlength=n) / self.den


def neighbors_1d(points: np.ndarray, nodes: np.ndarray, radius: float) -> NeighborTable:
    """All ``nodes`` with ``|x - y| < radius`` of each point, for **sorted** 1D ``nodes``.

    A vectorised ``searchsorted`` window (no compiled code, no per-point Python loop); returns
    the same CSR :class:`~mlsgalerkin.neighbors.NeighborTable` as ``find_neighbors``.
    """
    x = np.asarray(points, float).reshape(-1)
    y = np.asarray(nodes, float).reshape(-1)
    lo = np.searchsorted(y, x - radius, side="right")
    hi = np.searchsorted(y, x + radius, side="left")
    counts = np.maximum(hi - lo, 0)
    indptr = np.zeros(x.size + 1, dtype=np.int64)
    np.cumsum(counts, out=indptr[1:])
    offset = np.repeat(lo - indptr[:-1], counts)
    indices = (np.arange(indptr[-1], dtype=np.int64) + offset).astype(np.int32)
    return NeighborTable(indptr, indices, y.size)


def particle_sum(x: np.ndarray, kernel: str | Kernel, h: float) -> ParticleSum:
    """Neighbours (:func:`neighbors_1d`) and weights ``W_ab`` of sorted 1D particles ``x``."""
    k = get_kernel(kernel)
    pts = np.asarray(x, float).reshape(-1)
    nb = neighbors_1d(pts, pts, k.support * h)
    rows = nb.rows()
    cols = nb.indices
    # rounding q keeps mirror pairs bit-identical, so symmetric stencils stay symmetric
    q = np.round(np.abs(pts[rows] - pts[cols]) / h, 12)
    w = k.normalisation(1) / h * k.shape(q, 1)
    den = np.bincount(rows, w, minlength=pts.shape[0])
    return ParticleSum(rows, cols, w, den, nb.counts)


def particle_approximation(
    f: Callable[[np.ndarray], np.ndarray], x: np.ndarray, kernel: str | Kernel, h: float
) -> np.ndarray:
    r"""``<F(x_a)> = Σ_b F(x_b) W_ab / Σ_b W_ab`` at the particles ``x`` (Shepard-normalised)."""
    x = np.asarray(x, float)
    return particle_sum(x, kernel, h).apply(f(x))


# --------------------------------------------------------------------------------------
# part 1: the points of the SPH sweeps and their measurement
# --------------------------------------------------------------------------------------


def sph_points(cfg: StudyConfig) -> list[dict[str, Any]]:
    """Grid points of part 1: integral (h, N_nb) and particle (h, N) sweeps of every kernel."""
    points: list[dict[str, Any]] = []
    for kernel in cfg.sph_kernels:
        base = dict(part="sph", approximation="integral", kernel=kernel)
        points += [dict(base, sweep="h", h=h, n_neighbors=cfg.int_nnb_fixed) for h in cfg.int_h]
        points += [dict(base, sweep="n_neighbors", h=cfg.int_h_fixed, n_neighbors=n)
                   for n in cfg.int_nnb]
        base = dict(part="sph", approximation="particle", kernel=kernel)
        points += [dict(base, sweep="h", h=h, n_particles=cfg.part_n_fixed) for h in cfg.part_h]
        points += [dict(base, sweep="n_particles", h=cfg.part_h_fixed, n_particles=n)
                   for n in cfg.part_n]
    return points


def measure_integral(cfg: StudyConfig, kernel: str, sweep: str, h: float,
                     n_neighbors: int) -> list[dict[str, Any]]:
    """Rows (every function x region) of the integral approximation at ``h`` with
    ``n_neighbors`` quadrature points; ``wall_s`` is the best time of one approximation."""
    lo, hi = DOMAIN_1D
    x_eval = np.linspace(lo, hi, cfg.n_eval_1d)
    k = get_kernel(kernel)
    masks = {
        "interior": interior_mask(x_eval, k.support * h, lo, hi),
        "all": np.ones(x_eval.shape, bool),
    }
    dxq = 2.0 * k.support * h / n_neighbors
    rows = []
    for fn in FUNCTIONS:
        approx, t = best_time(
            lambda: integral_approximation(fn.f, x_eval, k, h, n_neighbors),
            cfg.min_time,
            cfg.repeats,
        )
        base = dict(
            part="sph",
            approximation="integral",
            layout="quadrature",
            kernel=kernel,
            function=fn.label,
            sweep=sweep,
            h=h,
            h_over_dx=h / dxq,
            n_particles=None,
            spacing=dxq,
            n_fallback=None,
        )
        rows += region_rows(base, masks, approx, fn.f(x_eval), wall_s=t,
                            counts=float(n_neighbors))
    return rows


def measure_particle(cfg: StudyConfig, kernel: str, sweep: str, h: float,
                     n_particles: int) -> list[dict[str, Any]]:
    """Rows of the particle approximation on ``n_particles`` equally spaced particles;
    ``wall_s`` is the best time of building the sum plus applying it to one function."""
    lo, hi = DOMAIN_1D
    k = get_kernel(kernel)
    x = np.linspace(lo, hi, n_particles)
    dx = (hi - lo) / (n_particles - 1)
    masks = {
        "interior": interior_mask(x, k.support * h, lo, hi),
        "all": np.ones(x.shape, bool),
    }
    ps, t_build = best_time(lambda: particle_sum(x, k, h), cfg.min_time, cfg.repeats)
    rows = []
    for fn in FUNCTIONS:
        fx = fn.f(x)
        approx, t = best_time(lambda: ps.apply(fn.f(x)), cfg.min_time, cfg.repeats)
        base = dict(
            part="sph",
            approximation="particle",
            layout="uniform",
            kernel=kernel,
            function=fn.label,
            sweep=sweep,
            h=h,
            h_over_dx=h / dx,
            n_particles=n_particles,
            spacing=dx,
            n_fallback=None,
        )
        rows += region_rows(base, masks, approx, fx, wall_s=t_build + t, counts=ps.counts)
    return rows
