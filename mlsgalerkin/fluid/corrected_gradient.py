r"""The renormalised (first-order corrected) kernel gradient of the density ratio, over the
fluid particles of each particle's own phase.

For a fluid particle ``i`` and the fluid neighbours ``j`` of its phase, with
:math:`\mathbf x_{ji} = \mathbf x_j - \mathbf x_i`, :math:`V_j = M_j/\rho_j` and the kernel
gradient :math:`\nabla_i W_{ij} = W'(r_{ij}, h_{ij})\,(\mathbf x_i - \mathbf x_j)/r_{ij}`
(``h_ij`` the mean smoothing length),

.. math::
    \mathbf A_i = \sum_j V_j\, \nabla_i W_{ij} \otimes \mathbf x_{ji},\qquad
    \mathbf g_i = \sum_j V_j\, (r_j - r_i)\, \nabla_i W_{ij},\qquad
    \langle\nabla r\rangle_i = \mathbf A_i^{-1}\,\mathbf g_i ,

with the density ratio :math:`r = \rho/\rho_0`. A linear field is differentiated exactly
whatever the neighbourhood (a truncated support at a free surface, a wall), which is what the
linear MLS approximation guarantees for the shape functions (Randles & Libersky 1996; the
"renormalised density gradient" of Antuono et al. 2010). ``A`` is symmetric and close to the
identity for a full support (``A ≈ 0.5 I`` on a flat free surface). Where its smallest
eigenvalue is below :data:`MIN_EIGENVALUE` (a splashing particle with a few neighbours) the
gradient is set to zero and the particle is flagged.

Used by :mod:`~mlsgalerkin.fluid.density_diffusion` (the δ-SPH correction of the diffusive
flux) and :mod:`~mlsgalerkin.fluid.shifting` (re-interpolating the density of a shifted
particle). A numba kernel, parallel over particles, with a numpy reference.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

from mlsgalerkin.kernels import kernel_f_df
from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period, minimum_image

__all__ = ["GRADIENT_FIELD", "MIN_EIGENVALUE", "ratio_gradient_mls", "ratio_gradient", "ratio_gradient_reference", "symmetric_min_eigenvalue"]

#: Smallest eigenvalue of ``A`` below which the corrected gradient is not trusted (set to 0).
MIN_EIGENVALUE = 0.1
#: The ``state.extra`` field (``(n, d)``, 1/m, zero on walls) where
#: :class:`~mlsgalerkin.fluid.density_diffusion.DensityDiffusion` (``"gradient"`` correction)
#: leaves the corrected gradient of ρ/ρ0 of its last evaluation; particle shifting reuses it.
GRADIENT_FIELD = "density_ratio_gradient"


@numba.njit(cache=True, inline="always")
def symmetric_min_eigenvalue(a00, a01, a02, a11, a12, a22, dim):
    """Smallest eigenvalue of the symmetric part of a 2×2 (``dim = 2``) or 3×3 matrix given by
    its upper triangle (closed forms; no allocation)."""
    if dim == 2:
        m = 0.5 * (a00 + a11)
        d = 0.5 * (a00 - a11)
        return m - math.sqrt(d * d + a01 * a01)
    # 3×3: trigonometric solution of the characteristic polynomial (Smith 1961)
    q = (a00 + a11 + a22) / 3.0
    p1 = a01 * a01 + a02 * a02 + a12 * a12
    p2 = (a00 - q) ** 2 + (a11 - q) ** 2 + (a22 - q) ** 2 + 2.0 * p1
    if p2 <= 1e-300:
        return q
    p = math.sqrt(p2 / 6.0)
    b00, b11, b22 = (a00 - q) / p, (a11 - q) / p, (a22 - q) / p
    b01, b02, b12 = a01 / p, a02 / p, a12 / p
    detb = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02)
    r = min(max(0.5 * detb, -1.0), 1.0)
    phi = math.acos(r) / 3.0
    return q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)


@numba.njit(parallel=True, cache=True)
def _ratio_gradient(x, ratio, volume, h, phase, indptr, indices, n_fluid, kid, support, norm_d, grad, trusted, period):
    dim = x.shape[1]
    for i in prange(n_fluid):
        # A (upper and lower triangle: A is symmetric up to round-off) and g in registers
        a00 = a01 = a02 = a11 = a12 = a22 = 0.0
        g0 = g1 = g2 = 0.0
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if j == i or j >= n_fluid or phase[j] != phase[i]:
                continue
            d0, d1, d2, r2 = pair_offset(x, i, j, period)   # x_ji = x_j − x_i
            if r2 <= 0.0:
                continue
            hij = 0.5 * (h[i] + h[j])
            r = math.sqrt(r2)
            qq = r / hij
            if qq >= support:
                continue
            _, df = kernel_f_df(kid, qq, support, dim)
            # V_j ∇_i W_ij = V_j W'(r) (x_i − x_j)/r = −s x_ji with s = V_j W'/r
            s = volume[j] * norm_d / hij ** (dim + 1) * df / r
            dr = ratio[j] - ratio[i]
            a00 -= s * d0 * d0
            a01 -= s * d0 * d1
            a02 -= s * d0 * d2
            a11 -= s * d1 * d1
            a12 -= s * d1 * d2
            a22 -= s * d2 * d2
            g0 -= s * d0 * dr
            g1 -= s * d1 * dr
            g2 -= s * d2 * dr
        lam = symmetric_min_eigenvalue(a00, a01, a02, a11, a12, a22, dim)
        if not lam >= MIN_EIGENVALUE:
            trusted[i] = False
            for c in range(dim):
                grad[i, c] = 0.0
            continue
        trusted[i] = True
        if dim == 2:
            det = a00 * a11 - a01 * a01
            grad[i, 0] = (a11 * g0 - a01 * g1) / det
            grad[i, 1] = (-a01 * g0 + a00 * g1) / det
        else:  # Cramer's rule for the symmetric 3×3 system
            c00 = a11 * a22 - a12 * a12
            c01 = a02 * a12 - a01 * a22
            c02 = a01 * a12 - a02 * a11
            c11 = a00 * a22 - a02 * a02
            c12 = a01 * a02 - a00 * a12
            c22 = a00 * a11 - a01 * a01
            det = a00 * c00 + a01 * c01 + a02 * c02
            grad[i, 0] = (c00 * g0 + c01 * g1 + c02 * g2) / det
            grad[i, 1] = (c01 * g0 + c11 * g1 + c12 * g2) / det
            grad[i, 2] = (c02 * g0 + c12 * g1 + c22 * g2) / det


def ratio_gradient(
    x: NDArray[np.float64], ratio: NDArray[np.float64], volume: NDArray[np.float64], h: NDArray[np.float64],
    phase: NDArray[np.int64], indptr: NDArray[np.int64], indices: NDArray[np.int32], n_fluid: int, kernel,
    period: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Corrected gradient ``(n_fluid, d)`` (1/m) of the density ratio ``r = ρ/ρ0`` and a
    ``(n_fluid,)`` flag of the particles where it is trusted (module docstring).

    ``x (n, d)`` m, ``ratio, volume (= M/ρ), h (n,)``, ``phase (n,)``, the CSR neighbour table
    of all particles against themselves (radius at least ``kernel.support · max h``); rows
    ``>= n_fluid`` (walls) are never partners. ``period (3,)`` (m): minimum-image offsets along
    the periodic axes (:mod:`mlsgalerkin.periodic`; default none).
    """
    dim = x.shape[1]
    grad = np.zeros((n_fluid, dim))
    trusted = np.zeros(n_fluid, dtype=np.bool_)
    _ratio_gradient(x, ratio, volume, h, phase, indptr, indices, n_fluid, kernel.kernel_id, float(kernel.support),
                    float(kernel.normalisation(dim)), grad, trusted, as_period(period))
    return grad, trusted


def ratio_gradient_mls(table, rho: NDArray[np.float64], rho0: NDArray[np.float64], p: NDArray[np.float64],
                       n_fluid: int, c0: float, gamma: float = 7.0) -> NDArray[np.float64]:
    """Gradient ``(n_fluid, d)`` (1/m) of the density ratio ``r = ρ/ρ0`` from the MLS gradient
    of the pressure, ``∇r_i = ∇p̃(x_i) / (ρ0_i c0² r_i^(γ−1))`` (the Tait curve,
    ``dp/dρ = c0² r^(γ−1)``), with ``p̃`` the Tait pressure of the current densities on the
    fluid particles and the wall model's pressure ``p`` on the wall particles.

    One gather over the shape-function ``table`` of this evaluation (about the cost of the
    velocity gradient, a fifth of a pass over the neighbours with kernel evaluations). The
    pressure is continuous across phases and walls, so a hydrostatic field has a linear ``p̃``,
    which MLS differentiates exactly, also at free surfaces and walls and across a density
    interface."""
    from mlsgalerkin.assembly import scalar_gradient

    ratio = rho / rho0
    pt = np.array(p, dtype=float)
    f = slice(0, n_fluid)
    pt[f] = rho0[f] * c0 * c0 / gamma * (ratio[f] ** gamma - 1.0)
    grad = scalar_gradient(table, pt, n_fluid)
    grad /= (rho0[f] * c0 * c0 * ratio[f] ** (gamma - 1.0))[:, None]
    return grad


def ratio_gradient_reference(x, ratio, volume, h, phase, indptr, indices, n_fluid, kernel, period=None):
    """Numpy version of :func:`ratio_gradient` (tests)."""
    dim = x.shape[1]
    grad = np.zeros((n_fluid, dim))
    trusted = np.zeros(n_fluid, dtype=bool)
    for i in range(n_fluid):
        nb = indices[indptr[i]:indptr[i + 1]].astype(np.int64)
        nb = nb[(nb != i) & (nb < n_fluid)]
        nb = nb[phase[nb] == phase[i]]
        xji = minimum_image(x[nb] - x[i], as_period(period))
        r = np.linalg.norm(xji, axis=1)
        hij = 0.5 * (h[i] + h[nb])
        keep = (r > 0) & (r < kernel.support * hij)
        nb, xji, r, hij = nb[keep], xji[keep], r[keep], hij[keep]
        dw = kernel.derivative(r, hij, dim)
        gw = -(volume[nb] * dw / r)[:, None] * xji          # V_j ∇_i W_ij
        A = gw.T @ xji                                      # symmetric: gw ∥ x_ji
        g = gw.T @ (ratio[nb] - ratio[i])
        if np.linalg.eigvalsh(0.5 * (A + A.T)).min() < MIN_EIGENVALUE:
            continue
        trusted[i] = True
        grad[i] = np.linalg.solve(A, g)
    return grad, trusted
