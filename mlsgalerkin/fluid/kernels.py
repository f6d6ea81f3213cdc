r"""Fused numba kernels of the fluid step (one pass over the pair table each).

``velocity_gradient_divergence``: ``L_k = Σ_j v_j ⊗ ∇N_j(x_k)`` and ``tr L_k`` in one gather,
accumulating in registers (no read-modify-write of the output inside the pair loop).

``internal_force_and_mass``: the Galerkin scatter of the internal force
``f_i = −Σ_k σ_k V_k ∇N_i(x_k)`` together with the lumped mass ``m_i = Σ_k N_i(x_k) M_k``
in one pass (one private accumulator per thread, one reduction).

Both equal the separate assembler functions of :mod:`mlsgalerkin.assembly` (their numpy
references are the ones tested there); ``tests/test_fluid_kernels.py`` checks the agreement.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import prange

from mlsgalerkin.assembly import _sum_slabs, _thread_blocks

__all__ = ["velocity_gradient_divergence", "internal_force_and_mass"]


@numba.njit(parallel=True, cache=True)
def _grad_div(indptr, indices, grads, v, L, div):
    n_rows = indptr.shape[0] - 1
    dim = grads.shape[1]
    for k in prange(n_rows):
        if dim == 2:
            l00 = l01 = l10 = l11 = 0.0
            for p in range(indptr[k], indptr[k + 1]):
                j = indices[p]
                gx = grads[p, 0]
                gy = grads[p, 1]
                vx = v[j, 0]
                vy = v[j, 1]
                l00 += vx * gx
                l01 += vx * gy
                l10 += vy * gx
                l11 += vy * gy
            L[k, 0, 0] = l00
            L[k, 0, 1] = l01
            L[k, 1, 0] = l10
            L[k, 1, 1] = l11
            div[k] = l00 + l11
        else:
            acc = np.zeros((3, 3))
            for p in range(indptr[k], indptr[k + 1]):
                j = indices[p]
                for a in range(dim):
                    va = v[j, a]
                    for b in range(dim):
                        acc[a, b] += va * grads[p, b]
            tr = 0.0
            for a in range(dim):
                tr += acc[a, a]
                for b in range(dim):
                    L[k, a, b] = acc[a, b]
            div[k] = tr


def velocity_gradient_divergence(table, v: np.ndarray, L: np.ndarray | None = None,
                                 div: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``L (n, d, d)`` and ``∇·v (n,)`` at the table's points; ``L``/``div`` reused if given."""
    n, d = table.n_points, table.dim
    if L is None or L.shape != (n, d, d):
        L = np.empty((n, d, d))
    if div is None or div.shape != (n,):
        div = np.empty(n)
    _grad_div(table.indptr, table.indices, table.gradients, v, L, div)
    return L, div


@numba.njit(parallel=True, cache=True)
def _force_mass(indptr, indices, values, grads, sig_v, M, n_nodes, n_blocks, want_mass):
    n_rows = indptr.shape[0] - 1
    dim = grads.shape[1]
    nc = dim + 1
    edges = _thread_blocks(n_rows, n_blocks)
    slab = np.zeros((n_blocks, n_nodes, nc))
    for blk in prange(n_blocks):
        for k in range(edges[blk], edges[blk + 1]):
            mk = M[k]
            for p in range(indptr[k], indptr[k + 1]):
                i = indices[p]
                for a in range(dim):
                    acc = 0.0
                    for b in range(dim):
                        acc += sig_v[k, a, b] * grads[p, b]
                    slab[blk, i, a] -= acc
                if want_mass:
                    slab[blk, i, dim] += values[p] * mk
    return _sum_slabs(slab)


def internal_force_and_mass(table, stress_volume: np.ndarray, masses: np.ndarray, n_threads: int,
                            want_mass: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """``f (n_nodes, d)`` with ``stress_volume = σ V`` ``(n, d, d)``, and ``m (n_nodes,)``."""
    out = _force_mass(table.indptr, table.indices, table.values, table.gradients, stress_volume, masses,
                      table.n_nodes, n_threads, want_mass)
    d = table.dim
    return np.ascontiguousarray(out[:, :d]), out[:, d].copy()
