r"""Nodal-integration Galerkin sums over a :class:`~mlsgalerkin.approximation.ShapeTable`.

The table is evaluated at the integration points ``k`` (the particles themselves for nodal
integration) against the nodes ``i``; pair ``p`` couples point ``k = row(p)`` and node
``i = indices[p]``. With point volumes ``V_k = M_k / ρ_k`` and masses ``M_k`` (Cueto-Felgueroso et al. 2005):

=====================  ============================================================  ===========
quantity               formula                                                        shape
=====================  ============================================================  ===========
lumped mass            ``m_i = Σ_k N_i(x_k) M_k``                                     (n_nodes,)
consistent mass        ``m_ij = Σ_k M_k N_i(x_k) N_j(x_k)``                           sparse
internal force         ``f_i = −Σ_k σ_k ∇N_i(x_k) V_k``                               (n_nodes, d)
body force             ``f_i = Σ_k N_i(x_k) b_k V_k``                                 (n_nodes, d)
traction               ``f_i = Σ_k N_i(x_k) t_k A_k`` (boundary points, areas A_k)   (n_nodes, d)
velocity gradient      ``L_k = Σ_j v_j ⊗ ∇N_j(x_k)``, ``L[a, b] = ∂v_a/∂x_b``         (n_points, d, d)
continuity rate        ``dρ_k/dt = −ρ_k tr L_k``                                      (n_points,)
integration residual   ``e_i = Σ_k ∇N_i(x_k) V_k`` (zero when exact, interior nodes)  (n_nodes, d)
=====================  ============================================================  ===========

Linear momentum is conserved because ``Σ_i ∇N_i = 0`` (so ``Σ_i f_int,i = 0`` for any stress),
angular momentum because ``Σ_i x_i ⊗ ∇N_i = I`` with a symmetric stress (linear basis).

Petrov–Galerkin: every function takes the *test* table; pass a different table for the test
functions than the one used for the trial field (``velocity_gradient``) to leave Bubnov–Galerkin.

The point → node sums run in numba as gathers: each node sums over its column of the table
(:meth:`ShapeTable.node_columns`, the pairs grouped by node) in ascending point order. The
parallel loop has no write races, and the result is the same, bit for bit, on any number of
threads (and equal to the serial scatter over the table's rows). ``*_reference`` functions are the numpy
versions (``scipy.sparse`` products) used by the agreement tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numba import prange
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.approximation.table import ShapeTable

__all__ = [
    "lumped_mass",
    "consistent_mass",
    "internal_force",
    "body_force",
    "traction_force",
    "velocity_gradient",
    "continuity_rate",
    "velocity_gradient_divergence",
    "scalar_gradient",
    "scalar_gradient_reference",
    "internal_force_and_mass",
    "internal_force_reference",
    "lumped_mass_reference",
    "velocity_gradient_reference",
    "IntegrationTerms",
    "integration_terms",
    "integration_terms_reference",
]

FloatArray = NDArray[np.float64]


def _per_point(name: str, a: ArrayLike, table: ShapeTable, trailing: tuple[int, ...] = ()) -> FloatArray:
    a = np.asarray(a, dtype=np.float64)
    want = (table.n_points, *trailing)
    if a.ndim == 0 and not trailing:
        a = np.full(table.n_points, float(a))
    if a.shape != want:
        raise ValueError(f"{name} must have shape {want} (one per integration point), got {a.shape}")
    if not np.isfinite(a).all():
        k = int(np.flatnonzero(~np.isfinite(a.reshape(a.shape[0], -1)).all(axis=1))[0])
        raise ValueError(f"{name} is not finite at integration point {k}")
    return np.ascontiguousarray(a)


def _per_node(name: str, a: ArrayLike, table: ShapeTable, trailing: tuple[int, ...]) -> FloatArray:
    a = np.asarray(a, dtype=np.float64)
    want = (table.n_nodes, *trailing)
    if a.shape != want:
        raise ValueError(f"{name} must have shape {want} (one per node), got {a.shape}")
    return np.ascontiguousarray(a)


# --------------------------------------------------------------------------------------
# compiled kernels
# --------------------------------------------------------------------------------------


@numba.njit(parallel=True, cache=True)
def _gather_weighted_values(col_ptr, col_pairs, col_rows, values, weight, n_nodes):
    """``out[i, c] = Σ_k N_i(x_k) weight[k, c]`` (a transposed sparse product), summed per node
    over its column (:meth:`ShapeTable.node_columns`) in ascending ``k``."""
    n_c = weight.shape[1]
    out = np.zeros((n_nodes, n_c))
    for i in prange(n_nodes):
        for t in range(col_ptr[i], col_ptr[i + 1]):
            p = col_pairs[t]
            k = col_rows[t]
            v = values[p]
            for c in range(n_c):
                out[i, c] += v * weight[k, c]
    return out


@numba.njit(parallel=True, cache=True)
def _force_mass(col_ptr, col_pairs, col_rows, values, grads, sig_v, M, n_nodes, want_mass):
    """``out[i, :d] = −Σ_k (σ V)_k ∇N_i(x_k)`` and, if ``want_mass``, ``out[i, d] = Σ_k N_i(x_k) M_k``,
    summed per node over its column in ascending ``k`` (``d`` = 1, 2 or 3)."""
    dim = grads.shape[1]
    out = np.zeros((n_nodes, dim + 1))
    for i in prange(n_nodes):
        f0 = f1 = f2 = m = 0.0
        for t in range(col_ptr[i], col_ptr[i + 1]):
            p = col_pairs[t]
            k = col_rows[t]
            if dim == 1:
                f0 -= sig_v[k, 0, 0] * grads[p, 0]
            elif dim == 2:
                f0 -= sig_v[k, 0, 0] * grads[p, 0] + sig_v[k, 0, 1] * grads[p, 1]
                f1 -= sig_v[k, 1, 0] * grads[p, 0] + sig_v[k, 1, 1] * grads[p, 1]
            else:
                f0 -= sig_v[k, 0, 0] * grads[p, 0] + sig_v[k, 0, 1] * grads[p, 1] + sig_v[k, 0, 2] * grads[p, 2]
                f1 -= sig_v[k, 1, 0] * grads[p, 0] + sig_v[k, 1, 1] * grads[p, 1] + sig_v[k, 1, 2] * grads[p, 2]
                f2 -= sig_v[k, 2, 0] * grads[p, 0] + sig_v[k, 2, 1] * grads[p, 1] + sig_v[k, 2, 2] * grads[p, 2]
            if want_mass:
                m += values[p] * M[k]
        out[i, 0] = f0
        if dim >= 2:
            out[i, 1] = f1
        if dim == 3:
            out[i, 2] = f2
        out[i, dim] = m
    return out


@numba.njit(parallel=True, cache=True)
def _scalar_grad(indptr, indices, grads, f, n_rows, out):
    """``out[k, b] = Σ_j f[j] ∂_b N_j(x_k)`` for the first ``n_rows`` points."""
    dim = grads.shape[1]
    for k in prange(n_rows):
        g0 = g1 = g2 = 0.0
        for p in range(indptr[k], indptr[k + 1]):
            fj = f[indices[p]]
            g0 += fj * grads[p, 0]
            g1 += fj * grads[p, 1]
            if dim == 3:
                g2 += fj * grads[p, 2]
        out[k, 0] = g0
        out[k, 1] = g1
        if dim == 3:
            out[k, 2] = g2


@numba.njit(parallel=True, cache=True)
def _grad_div(indptr, indices, grads, v, L, div):
    """``L[k, a, b] = Σ_j v[j, a] ∂_b N_j(x_k)`` and ``div[k] = tr L_k``, accumulated in registers."""
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


@numba.njit(parallel=True, cache=True)
def _integration_terms(col_ptr, col_pairs, col_rows, values, grads, V, sig_v, c, n_nodes):
    """Per node ``i``: ``e_i = Σ_k V_k ∇N_i(x_k)`` (columns ``:d``), ``w_i = Σ_k V_k N_i(x_k)``
    (column ``d``), ``S_i = Σ_k N_i(x_k) (σV)_k`` (columns ``d+1:``, row-major ``d × d``), and
    ``min_k c_k`` over the points whose row holds ``i`` (column ``nc``), summed per node over its
    column in ascending ``k``."""
    dim = grads.shape[1]
    nc = dim + 1 + dim * dim
    out = np.zeros((n_nodes, nc + 1))
    for i in prange(n_nodes):
        lowest = np.inf
        for t in range(col_ptr[i], col_ptr[i + 1]):
            p = col_pairs[t]
            k = col_rows[t]
            vk = V[k]
            nv = values[p]
            for a in range(dim):
                out[i, a] += vk * grads[p, a]
            out[i, dim] += vk * nv
            for a in range(dim):
                for b in range(dim):
                    out[i, dim + 1 + a * dim + b] += nv * sig_v[k, a, b]
            if c[k] < lowest:
                lowest = c[k]
        out[i, nc] = lowest
    return out


# --------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------


def lumped_mass(table: ShapeTable, masses: ArrayLike) -> FloatArray:
    """Row-sum (lumped) mass ``m_i = Σ_k N_i(x_k) M_k``, ``(n_nodes,)`` in kg.

    ``masses``: ``(n_points,)`` physical point masses ``M_k`` in kg. Because the shape
    functions are a partition of unity, ``Σ_i m_i = Σ_k M_k``.
    """
    M = _per_point("masses", masses, table)
    cols = table.node_columns()
    return _gather_weighted_values(cols.indptr, cols.pairs, cols.rows, table.values, M[:, None], table.n_nodes)[:, 0]


def consistent_mass(table: ShapeTable, masses: ArrayLike):
    """Consistent mass ``m_ij = Σ_k M_k N_i(x_k) N_j(x_k)`` as a ``scipy.sparse.csr_array``.

    Rows sum to the lumped mass (partition of unity).
    """
    from scipy.sparse import csr_array, diags_array

    M = _per_point("masses", masses, table)
    N = table.value_matrix()
    return csr_array(N.T @ diags_array(M) @ N)


def internal_force(table: ShapeTable, stress: ArrayLike, volumes: ArrayLike) -> FloatArray:
    r"""Internal nodal force ``f_i = −Σ_k σ_k ∇N_i(x_k) V_k``, ``(n_nodes, dim)`` in N.

    ``stress``: ``(n_points, dim, dim)`` Cauchy stress in Pa; ``volumes``: ``(n_points,)`` in
    m^dim. ``Σ_i f_i = 0`` for any stress (momentum conservation).
    """
    d = table.dim
    sig = _per_point("stress", stress, table, (d, d))
    V = _per_point("volumes", volumes, table)
    return internal_force_and_mass(table, sig * V[:, None, None], V, want_mass=False)[0]


def body_force(table: ShapeTable, body: ArrayLike, volumes: ArrayLike) -> FloatArray:
    """External body force ``f_i = Σ_k N_i(x_k) b_k V_k``, ``(n_nodes, dim)``.

    ``body``: ``(n_points, dim)`` force per unit volume (e.g. ``ρ g``) in N/m^dim.
    """
    b = _per_point("body", body, table, (table.dim,))
    V = _per_point("volumes", volumes, table)
    cols = table.node_columns()
    return _gather_weighted_values(cols.indptr, cols.pairs, cols.rows, table.values, b * V[:, None], table.n_nodes)


def traction_force(boundary_table: ShapeTable, traction: ArrayLike, areas: ArrayLike) -> FloatArray:
    """Boundary traction force ``f_i = Σ_k N_i(x_k) t_k A_k`` over boundary points ``k``.

    ``boundary_table``: shape functions at the boundary quadrature points; ``traction``:
    ``(n_points, dim)`` in Pa; ``areas``: ``(n_points,)`` boundary measure in m^(dim-1).
    """
    return body_force(boundary_table, traction, areas)


def velocity_gradient(table: ShapeTable, velocity: ArrayLike) -> FloatArray:
    """``L_k = Σ_j v_j ⊗ ∇N_j(x_k)``, ``(n_points, dim, dim)`` with ``L[k, a, b] = ∂v_a/∂x_b``."""
    v = _per_node("velocity", velocity, table, (table.dim,))
    return velocity_gradient_divergence(table, v)[0]


def continuity_rate(table: ShapeTable, velocity: ArrayLike, density: ArrayLike) -> FloatArray:
    """Collocated continuity ``dρ_k/dt = −ρ_k tr ∇v(x_k)``, ``(n_points,)`` in kg/m^d/s."""
    rho = _per_point("density", density, table)
    v = _per_node("velocity", velocity, table, (table.dim,))
    return -rho * velocity_gradient_divergence(table, v)[1]


def velocity_gradient_divergence(table: ShapeTable, v: FloatArray, L: FloatArray | None = None,
                                 div: FloatArray | None = None) -> tuple[FloatArray, FloatArray]:
    """``L (n_points, d, d)`` and ``∇·v = tr L (n_points,)`` in one gather, without input checks.

    For time-stepping solvers: ``v (n_nodes, d)`` must be C-contiguous float64; ``L`` and
    ``div`` are reused as output buffers when they have the right shapes.
    """
    n, d = table.n_points, table.dim
    if L is None or L.shape != (n, d, d):
        L = np.empty((n, d, d))
    if div is None or div.shape != (n,):
        div = np.empty(n)
    _grad_div(table.indptr, table.indices, table.gradients, v, L, div)
    return L, div


def scalar_gradient(table: ShapeTable, f: FloatArray, n_rows: int | None = None) -> FloatArray:
    """Gradient ``(n_rows, d)`` of the approximation of a nodal scalar ``f (n_nodes,)`` at the
    first ``n_rows`` points (default all), ``∇f(x_k) = Σ_j f_j ∇N_j(x_k)``, in one gather
    without input checks (for solvers; ``f`` C-contiguous float64)."""
    n = table.n_points if n_rows is None else int(n_rows)
    out = np.empty((n, table.dim))
    _scalar_grad(table.indptr, table.indices, table.gradients, f, n, out)
    return out


def scalar_gradient_reference(table: ShapeTable, f: FloatArray, n_rows: int | None = None) -> FloatArray:
    """Numpy version of :func:`scalar_gradient` (tests)."""
    G = table.gradient_matrices()
    n = table.n_points if n_rows is None else int(n_rows)
    return np.stack([G[b] @ np.asarray(f, dtype=float) for b in range(table.dim)], axis=1)[:n]


def internal_force_and_mass(table: ShapeTable, stress_volume: FloatArray, masses: FloatArray,
                            want_mass: bool = True) -> tuple[FloatArray, FloatArray]:
    """Internal force ``f (n_nodes, d)`` from ``stress_volume = σ V (n_points, d, d)`` and the
    lumped mass ``m (n_nodes,)`` from ``masses (n_points,)`` in one scatter, without input
    checks (for solvers); ``m`` is zero when ``want_mass`` is False."""
    cols = table.node_columns()
    out = _force_mass(cols.indptr, cols.pairs, cols.rows, table.values, table.gradients, stress_volume, masses,
                      table.n_nodes, want_mass)
    d = table.dim
    return np.ascontiguousarray(out[:, :d]), out[:, d].copy()


@dataclass(frozen=True)
class IntegrationTerms:
    """Node sums that measure how well nodal integration meets the integration constraint
    (:func:`integration_terms`); shapes for ``n`` nodes in ``d`` dimensions.

    ``residual (n, d)``: ``e_i = Σ_k ∇N_i(x_k) V_k`` (m^(d−1)); the exact ``∫∇N_i dΩ`` is zero
    for a node whose support lies inside the domain. ``volume (n,)``: ``w_i = Σ_k N_i(x_k) V_k``
    (m^d). ``stress_volume (n, d, d)``: ``S_i = Σ_k N_i(x_k) σ_k V_k`` (N m^(d−2)), so
    ``S_i / w_i`` is the ``N_i``-weighted mean stress. ``lowest (n,)``: the smallest of a
    per-point scalar over the points whose row holds node ``i`` (``inf`` for a node in no row).
    """

    residual: FloatArray
    volume: FloatArray
    stress_volume: FloatArray
    lowest: FloatArray


def integration_terms(table: ShapeTable, volumes: FloatArray, stress_volume: FloatArray,
                      point_scalar: FloatArray) -> IntegrationTerms:
    """:class:`IntegrationTerms` in one scatter, without input checks (for solvers):
    ``volumes (n_points,)``, ``stress_volume = σ V (n_points, d, d)``, ``point_scalar (n_points,)``,
    all C-contiguous float64."""
    d = table.dim
    cols = table.node_columns()
    out = _integration_terms(cols.indptr, cols.pairs, cols.rows, table.values, table.gradients, volumes,
                             stress_volume, point_scalar, table.n_nodes)
    return IntegrationTerms(np.ascontiguousarray(out[:, :d]), out[:, d].copy(),
                            np.ascontiguousarray(out[:, d + 1:-1]).reshape(-1, d, d), out[:, -1].copy())


# --------------------------------------------------------------------------------------
# numpy references (tests)
# --------------------------------------------------------------------------------------


def lumped_mass_reference(table: ShapeTable, masses: FloatArray) -> FloatArray:
    return table.value_matrix().T @ np.asarray(masses, dtype=float)


def internal_force_reference(table: ShapeTable, stress: FloatArray, volumes: FloatArray) -> FloatArray:
    G = table.gradient_matrices()
    sv = np.asarray(stress) * np.asarray(volumes)[:, None, None]
    return -np.stack([sum(G[b].T @ sv[:, a, b] for b in range(table.dim)) for a in range(table.dim)], axis=1)


def velocity_gradient_reference(table: ShapeTable, velocity: FloatArray) -> FloatArray:
    G = table.gradient_matrices()
    return np.stack([G[b] @ velocity for b in range(table.dim)], axis=-1)


def integration_terms_reference(table: ShapeTable, volumes: FloatArray, stress_volume: FloatArray,
                                point_scalar: FloatArray) -> IntegrationTerms:
    """Numpy version of :func:`integration_terms` (tests)."""
    N = table.value_matrix()
    G = table.gradient_matrices()
    d = table.dim
    e = np.stack([G[b].T @ volumes for b in range(d)], axis=1)
    w = N.T @ volumes
    S = np.stack([np.stack([N.T @ stress_volume[:, a, b] for b in range(d)], axis=-1) for a in range(d)], axis=1)
    rows = np.repeat(np.arange(table.n_points), np.diff(table.indptr))
    low = np.full(table.n_nodes, np.inf)
    np.minimum.at(low, table.indices, np.asarray(point_scalar)[rows])
    return IntegrationTerms(e, w, S, low)
