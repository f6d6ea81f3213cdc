r"""Stabilisation of the nodally integrated viscous term: a compact pair Laplacian of the part
of the velocity that the nodal gradients do not see.

**Why.** With nodal integration the viscous force is ``−Σ_k σ_k ∇N_i(x_k) V_k`` with
``σ_k = μ (L_k + L_kᵀ − ⅔ tr L_k I)`` and ``L_k`` the MLS velocity gradient at the nodes: the
Laplacian is built from two first derivatives, a wide stencil. A velocity that alternates from
one row of particles to the next has (nearly) zero nodal gradient, so it feels (nearly) no
viscosity — a zero-energy mode of the nodal integration. Measured in plane Couette flow
(``problems/couette.py``, H/Δx = 20, exact wall velocities, no shifting): an alternation of
±13 % of the wall speed survives a run to steady state; and the Taylor–Green vortex decays
too slowly (its modes of short wavelength feel a viscosity that is too small).

**What.** A pair force on the residual of the velocity from the linear field of the two nodal
gradients (the hourglass control of Ganzenmüller 2015, applied to the velocity), in the
compact form of Morris, Fox & Zhu (1997)'s SPH viscous term:

.. math::
    \mathbf e_{ij} = \mathbf v_i - \mathbf v_j - \tfrac12(\mathbf L_i + \mathbf L_j)\,\mathbf x_{ij},
    \qquad
    \mathbf f_i = \sum_j (\mu_i + \mu_j)\, V_i V_j\,
        \frac{\mathbf x_{ij}\cdot\nabla_i W_{ij}}{|\mathbf x_{ij}|^2 + 0.01 h_{ij}^2}\,\mathbf e_{ij},

``x_ij = x_i − x_j``, ``V = M/ρ``, ``h_ij`` the mean smoothing length, ``W`` the normalised
kernel. ``x_ij·∇_iW = r dW/dr ≤ 0``, so the force pulls ``v_i`` towards the linear continuation
of its neighbours' velocities. Properties (tested): it vanishes for any linear velocity field
(``e_ij = 0``; the Couette profile is untouched), and for a quadratic one on a regular lattice
(the mean of the two exact gradients is the gradient at the midpoint); it is antisymmetric in
``i, j`` (linear momentum conserved to round-off when both are active); and for an alternating
mode, whose nodal gradient vanishes, it is Morris's viscous force — the physical damping of
the mode. Units: ``μ`` Pa s, ``V`` m^d, ``f`` N (N/m in 2D).

The compiled loop is the gather form over a symmetric table (each row ``i`` sums its own
neighbours; no scatter).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

from mlsgalerkin.kernels import Kernel, kernel_f_df
from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period, minimum_image

__all__ = ["viscous_residual_force", "viscous_residual_force_reference"]

#: ``0.01 h²`` regulariser of the pair denominator (Morris, Fox & Zhu 1997).
ETA_SQUARED = 0.01


@numba.njit(parallel=True, cache=True)
def _residual_kernel(x, v, L, mu, vol, h, indptr, indices, kid, support, norm_d, active, period):
    n, dim = x.shape
    force = np.zeros((n, dim))
    rows = np.nonzero(active)[0]
    for k in prange(rows.shape[0]):
        i = rows[k]
        f0 = 0.0
        f1 = 0.0
        f2 = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            if j == i:
                continue
            d0, d1, d2, r2 = pair_offset(x, i, j, period)   # x_ji; x_ij is its negation
            if r2 <= 0.0:
                continue
            hij = 0.5 * (h[i] + h[j])
            r = math.sqrt(r2)
            q = r / hij
            if q >= support:
                continue
            dij = (-d0, -d1, -d2)
            e0 = v[i, 0] - v[j, 0]
            e1 = v[i, 1] - v[j, 1] if dim > 1 else 0.0
            e2 = v[i, 2] - v[j, 2] if dim > 2 else 0.0
            for b in range(dim):
                e0 -= 0.5 * (L[i, 0, b] + L[j, 0, b]) * dij[b]
                if dim > 1:
                    e1 -= 0.5 * (L[i, 1, b] + L[j, 1, b]) * dij[b]
                if dim > 2:
                    e2 -= 0.5 * (L[i, 2, b] + L[j, 2, b]) * dij[b]
            _, dfdq = kernel_f_df(kid, q, support, dim)
            dwdr = norm_d / hij ** (dim + 1) * dfdq
            c = (mu[i] + mu[j]) * vol[i] * vol[j] * r * dwdr / (r2 + ETA_SQUARED * hij * hij)
            f0 += c * e0
            f1 += c * e1
            f2 += c * e2
        force[i, 0] = f0
        if dim > 1:
            force[i, 1] = f1
        if dim > 2:
            force[i, 2] = f2
    return force


def viscous_residual_force(
    x: NDArray[np.float64], v: NDArray[np.float64], L: NDArray[np.float64], mu: NDArray[np.float64],
    volume: NDArray[np.float64], h: NDArray[np.float64], indptr: NDArray[np.int64], indices: NDArray[np.int32],
    kernel: Kernel, active: NDArray[np.bool_], period: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """The stabilising force ``(n, d)`` (N; module docstring) on the ``active`` particles.

    ``x, v (n, d)`` m, m/s; ``L (n, d, d)`` 1/s, ``L[i, a, b] = ∂v_a/∂x_b``; ``mu (n,)`` Pa s;
    ``volume (n,)`` m^d; ``h (n,)`` m; ``indptr, indices``: a symmetric CSR neighbour table of
    the particles against themselves reaching at least ``support·h``; ``active (n,)`` bool
    (inactive rows are zero, inactive particles still act as partners); ``period (3,)`` m.
    """
    return _residual_kernel(
        x, v, np.ascontiguousarray(L), mu, volume, h, indptr, indices, kernel.kernel_id, float(kernel.support),
        float(kernel.normalisation(x.shape[1])), active, as_period(period),
    )


def viscous_residual_force_reference(x, v, L, mu, volume, h, indptr, indices, kernel, active, period=None):
    """Numpy version of :func:`viscous_residual_force` (vectorised over pairs; tests)."""
    n, dim = x.shape
    rows = np.repeat(np.arange(n), np.diff(indptr))
    cols = np.asarray(indices, dtype=np.int64)
    dij = -minimum_image(x[cols] - x[rows], as_period(period))
    r2 = np.einsum("pd,pd->p", dij, dij)
    hij = 0.5 * (h[rows] + h[cols])
    r = np.sqrt(r2)
    keep = active[rows] & (cols != rows) & (r2 > 0) & (r < kernel.support * hij)
    rows, cols, dij, r2, hij, r = (a[keep] for a in (rows, cols, dij, r2, hij, r))
    e = v[rows] - v[cols] - 0.5 * np.einsum("pab,pb->pa", L[rows] + L[cols], dij)
    c = (mu[rows] + mu[cols]) * volume[rows] * volume[cols] * r * kernel.derivative(r, hij, dim) / (
        r2 + ETA_SQUARED * hij**2)
    return np.stack([np.bincount(rows, c * e[:, a], minlength=n) for a in range(dim)], axis=1)
