"""Readable numpy reference for MLS/RKPM/Shepard shape functions (tests only; slow).

One point at a time, dense algebra, ``numpy.linalg.solve``; the same fallback policy as the
compiled kernels, so both can be compared pair by pair.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.kernels import Kernel
from mlsgalerkin.neighbors import NeighborTable
from mlsgalerkin.periodic import as_period, minimum_image
from mlsgalerkin.polynomials import basis_size, evaluate_basis_numpy

__all__ = ["reference_shape_functions"]


def reference_shape_functions(
    points: NDArray[np.float64],
    nodes: NDArray[np.float64],
    h: NDArray[np.float64],
    neighbors: NeighborTable,
    kernel: Kernel,
    order: int,
    volumes: NDArray[np.float64] | None = None,
    cond_limit: float = 1e8,
    period: NDArray[np.float64] | None = None,
) -> tuple[NDArray, NDArray, NDArray]:
    """Per-pair ``values (n_pairs,)``, ``gradients (n_pairs, dim)`` and per-point ``order``
    (``period (3,)`` m: minimum-image offsets along the periodic axes; default none)."""
    period = as_period(period)
    dim = points.shape[1]
    values = np.zeros(neighbors.n_pairs)
    grads = np.zeros((neighbors.n_pairs, dim))
    used = np.full(points.shape[0], -1)
    for i in range(points.shape[0]):
        sl = slice(neighbors.indptr[i], neighbors.indptr[i + 1])
        j = neighbors.indices[sl]
        dx = -minimum_image(nodes[j] - points[i], period)  # (n, dim), x - x_j
        r = np.linalg.norm(dx, axis=1)
        hj = h[j]
        v = volumes[j] if volumes is not None else 1.0
        w = kernel.shape(r / hj, dim) / hj**dim * v
        dwdr = kernel.shape_derivative(r / hj, dim) / hj ** (dim + 1) * v
        dw = np.where(r[:, None] > 0, dwdr[:, None] * dx / np.where(r > 0, r, 1)[:, None], 0.0)
        s = hj.mean()
        for o in range(order, -1, -1):
            P = evaluate_basis_numpy(-dx / s, o)  # (n, m)
            M = P.T @ (w[:, None] * P)
            try:
                np.linalg.cholesky(M)
                Minv = np.linalg.inv(M)
            except np.linalg.LinAlgError:
                continue
            if np.linalg.norm(M, 1) * np.linalg.norm(Minv, 1) > cond_limit:
                continue
            m = basis_size(dim, o)
            e0 = np.zeros(m)
            e0[0] = 1.0
            gam = np.linalg.solve(M, e0)
            cg = P @ gam
            values[sl] = cg * w
            for k in range(dim):
                dM = P.T @ (dw[:, k, None] * P)
                dp = np.zeros(m)
                if o >= 1:
                    dp[1 + k] = 1.0 / s
                dgam = np.linalg.solve(M, dp - dM @ gam)
                grads[sl, k] = (P @ dgam) * w + cg * dw[:, k]
            used[i] = o
            break
    return values, grads, used
