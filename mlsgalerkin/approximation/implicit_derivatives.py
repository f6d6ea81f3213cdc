r"""Implicit second derivatives: a quadratic moving least-squares fit read off at its centre.

For a point :math:`\mathbf x` with neighbours :math:`\mathbf x_j` (the nodes whose supports
contain it), offsets :math:`\boldsymbol\xi_j = (\mathbf x_j - \mathbf x)/\ell` and weights
:math:`w_j = W(|\mathbf x_j - \mathbf x|, h_j)`, the quadratic basis
:math:`\mathbf P(\boldsymbol\xi) = [1, \xi_1, …, \xi_d, \xi_1^2, \xi_1\xi_2, …, \xi_d^2]` (every
monomial of degree ≤ 2, :func:`~mlsgalerkin.polynomials.monomial_exponents`) gives the moment
matrix :math:`\mathbf A = \sum_j w_j \mathbf P_j \mathbf P_j^T` and the second-derivative
functions

.. math::

    \Psi^{(ab)}_j(\mathbf x) = \frac{c_{ab}}{\ell^2}\, \mathbf e_{ab}^T \mathbf A^{-1} \mathbf P_j\, w_j,
    \qquad c_{aa} = 2,\; c_{a\ne b} = 1,

where :math:`\mathbf e_{ab}` picks the monomial :math:`\xi_a\xi_b`. They reproduce second
derivatives of quadratics exactly, :math:`\sum_j \Psi^{(ab)}_j f(\mathbf x_j) = \partial_a\partial_b f(\mathbf x)`
for every polynomial ``f`` of degree ≤ 2, and need no derivative of the kernel or of the moment
matrix: the *implicit* (gradient reproducing kernel, or diffuse) derivatives of Chi, Chen, Hu &
Yang (2013), which Hillman & Chen (2016) use for the strain gradients of naturally stabilised
nodal integration. The exact second derivatives of a linear MLS approximation (differentiating
:math:`\mathbf M \boldsymbol\gamma = \mathbf p` twice) are a different, costlier object; these
are what a stabilisation of nodal integration needs: ``∇(∇·v)`` at the nodes from the nodal
velocities.

A point whose neighbours cannot fix a quadratic (too few, or all on a line, or a moment matrix
whose 1-norm condition number, scaled, passes ``condition_limit``) gets zero rows and
``ok = False``; nothing is guessed there.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.kernels import Kernel, get_kernel
from mlsgalerkin.neighbors import NeighborTable
from mlsgalerkin.periodic import as_period
from mlsgalerkin.polynomials import evaluate_basis, evaluate_basis_numpy, monomial_exponents

__all__ = ["DEFAULT_CONDITION_LIMIT", "implicit_second_derivatives", "implicit_second_derivatives_reference"]

#: Largest accepted 1-norm condition number of the scaled quadratic moment matrix.
DEFAULT_CONDITION_LIMIT = 1.0e8


def _second_derivative_slots(dim: int) -> NDArray[np.int64]:
    """``slot[a, b]``: the index of the monomial ``ξ_a ξ_b`` in the quadratic basis ``(dim, dim)``."""
    exps = monomial_exponents(dim, 2)
    slots = np.empty((dim, dim), dtype=np.int64)
    for a in range(dim):
        for b in range(dim):
            e = np.zeros(dim, dtype=np.int64)
            e[a] += 1
            e[b] += 1
            slots[a, b] = int(np.flatnonzero((exps == e).all(axis=1))[0])
    return slots


def _offsets(points: NDArray, nodes: NDArray, rows: NDArray, cols: NDArray, period: NDArray) -> NDArray:
    """``x_j − x`` per pair ``(n_pairs, dim)``, the minimum image along periodic axes."""
    off = nodes[cols] - points[rows]
    for a in range(off.shape[1]):
        if period[a] > 0:
            off[:, a] -= period[a] * np.round(off[:, a] / period[a])
    return off


@numba.njit(cache=True)
def _implicit_hessians(indptr, offsets, weights, scale, exps, slots, condition_limit, out, ok):
    """Numba kernel of :func:`implicit_second_derivatives` (one point per row of ``indptr``)."""
    n = indptr.size - 1
    dim = offsets.shape[1]
    m = exps.shape[0]
    P = np.empty(m)
    xi = np.empty(dim)
    for k in range(n):
        lo, hi = indptr[k], indptr[k + 1]
        ok[k] = False
        for p in range(lo, hi):
            for a in range(dim):
                for b in range(dim):
                    out[p, a, b] = 0.0
        if hi - lo < m:
            continue
        A = np.zeros((m, m))
        for p in range(lo, hi):
            for a in range(dim):
                xi[a] = offsets[p, a] / scale[k]
            evaluate_basis(xi, exps, m, P)
            for a in range(m):
                for b in range(m):
                    A[a, b] += weights[p] * P[a] * P[b]
        if np.linalg.matrix_rank(A) < m:
            continue
        Ainv = np.linalg.inv(A)
        if not np.linalg.norm(A, 1) * np.linalg.norm(Ainv, 1) <= condition_limit:   # 1-norm condition
            continue
        ok[k] = True
        l2 = scale[k] * scale[k]
        for p in range(lo, hi):
            for a in range(dim):
                xi[a] = offsets[p, a] / scale[k]
            evaluate_basis(xi, exps, m, P)
            for a in range(dim):
                for b in range(a, dim):
                    s = 0.0
                    row = slots[a, b]
                    for c in range(m):
                        s += Ainv[row, c] * P[c]
                    v = (2.0 if a == b else 1.0) * s * weights[p] / l2
                    out[p, a, b] = v
                    out[p, b, a] = v


def _prepare(points: ArrayLike, nodes: ArrayLike, h: ArrayLike, neighbors: NeighborTable,
             kernel: str | Kernel, period: ArrayLike | None):
    """Pair offsets, kernel weights and per-point length scales (the mean ``h`` of each
    point's neighbours), checked."""
    x = np.atleast_2d(np.asarray(points, dtype=float))
    xn = np.atleast_2d(np.asarray(nodes, dtype=float))
    if x.ndim != 2 or xn.ndim != 2 or x.shape[1] != xn.shape[1] or not 1 <= x.shape[1] <= 3:
        raise ValueError(f"points {x.shape} and nodes {xn.shape} must be (n, dim) arrays of one dimension 1-3")
    dim = x.shape[1]
    h_a = np.broadcast_to(np.asarray(h, dtype=float), (xn.shape[0],))
    if not np.all(h_a > 0):
        raise ValueError("h must be positive for every node")
    if neighbors.n_points != x.shape[0] or neighbors.n_nodes != xn.shape[0]:
        raise ValueError(f"neighbors table is {neighbors.n_points} points x {neighbors.n_nodes} nodes, "
                         f"expected {x.shape[0]} x {xn.shape[0]}")
    kern = get_kernel(kernel)
    if not kern.nonnegative:
        raise ValueError(f"kernel {kern.name!r} takes negative values inside its support; use a non-negative "
                         "kernel (e.g. 'cubic_spline', 'wendland_c2') for a least-squares fit")
    per = np.asarray(as_period(period), dtype=float)[:dim]
    indptr = np.asarray(neighbors.indptr, dtype=np.int64)
    cols = np.asarray(neighbors.indices, dtype=np.int64)
    rows = np.repeat(np.arange(x.shape[0]), np.diff(indptr))
    off = _offsets(x, xn, rows, cols, per)
    r = np.sqrt(np.einsum("pa,pa->p", off, off))
    weights = kern.value(r, h_a[cols], dim) * h_a[cols] ** dim     # dimensionless: W h^d
    counts = np.diff(indptr)
    scale = np.where(counts > 0, np.bincount(rows, h_a[cols], minlength=x.shape[0]) / np.maximum(counts, 1), 1.0)
    return indptr, off, weights, scale, dim


def implicit_second_derivatives(
    points: ArrayLike,
    nodes: ArrayLike,
    h: ArrayLike,
    neighbors: NeighborTable,
    kernel: str | Kernel = "cubic_spline",
    *,
    period: ArrayLike | None = None,
    condition_limit: float = DEFAULT_CONDITION_LIMIT,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    r"""Implicit second derivatives :math:`\Psi^{(ab)}_j(\mathbf x_k) ≈ \partial_a\partial_b N_j(\mathbf x_k)`
    of the quadratic least-squares fit (module docstring), per pair of ``neighbors``.

    Parameters
    ----------
    points : (n_points, dim) float array (m)
    nodes : (n_nodes, dim) float array (m)
    h : float or (n_nodes,) float array
        Smoothing length of each node (m); the weight of node ``j`` is ``W(|x_j − x|, h_j)``.
    neighbors : NeighborTable
        The nodes near each point (:func:`~mlsgalerkin.neighbors.find_neighbors`); its pair
        order is the output's.
    kernel : name or :class:`~mlsgalerkin.kernels.Kernel` (non-negative)
    period : one value per axis, optional
        Periodic axes (``0``: not periodic): offsets are minimum images.
    condition_limit : float
        Largest accepted 1-norm condition number of the scaled moment matrix.

    Returns
    -------
    hessians : (n_pairs, dim, dim) float array (1/m²)
        Symmetric in its last two axes; ``Σ_j hessians[p(k, j)] f_j`` is the Hessian of ``f`` at
        point ``k``, exact for quadratics.
    ok : (n_points,) bool array
        ``False`` where the neighbours cannot fix a quadratic (those rows are zero).
    """
    if not condition_limit > 1.0:
        raise ValueError(f"condition_limit must exceed 1, got {condition_limit!r}")
    indptr, off, weights, scale, dim = _prepare(points, nodes, h, neighbors, kernel, period)
    exps = monomial_exponents(dim, 2)
    out = np.empty((off.shape[0], dim, dim))
    ok = np.empty(indptr.size - 1, dtype=np.bool_)
    _implicit_hessians(indptr, np.ascontiguousarray(off), weights, scale, exps, _second_derivative_slots(dim),
                       float(condition_limit), out, ok)
    return out, ok


def implicit_second_derivatives_reference(
    points: ArrayLike, nodes: ArrayLike, h: ArrayLike, neighbors: NeighborTable,
    kernel: str | Kernel = "cubic_spline", *, period: ArrayLike | None = None,
    condition_limit: float = DEFAULT_CONDITION_LIMIT,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Numpy version of :func:`implicit_second_derivatives` (tests): one least-squares solve per point."""
    indptr, off, weights, scale, dim = _prepare(points, nodes, h, neighbors, kernel, period)
    slots = _second_derivative_slots(dim)
    m = monomial_exponents(dim, 2).shape[0]
    out = np.zeros((off.shape[0], dim, dim))
    ok = np.zeros(indptr.size - 1, dtype=bool)
    for k in range(indptr.size - 1):
        sl = slice(indptr[k], indptr[k + 1])
        P = evaluate_basis_numpy(off[sl] / scale[k], 2)              # (n_j, m)
        if P.shape[0] < m:
            continue
        A = (P * weights[sl, None]).T @ P
        if np.linalg.matrix_rank(A) < m or np.linalg.cond(A, 1) > condition_limit:
            continue
        ok[k] = True
        coef = np.linalg.solve(A, (P * weights[sl, None]).T)        # (m, n_j): A⁻¹ P_j w_j
        c = np.where(np.eye(dim, dtype=bool), 2.0, 1.0)
        out[sl] = (c[None] * coef[slots].transpose(2, 0, 1)) / scale[k] ** 2
    return out, ok
