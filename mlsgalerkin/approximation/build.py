r"""Build MLS / RKPM / Shepard / orthogonal shape functions with exact gradients.

>>> import numpy as np, mlsgalerkin
>>> nodes = np.random.default_rng(0).random((400, 2))
>>> table = mlsgalerkin.shape_functions(nodes, nodes, h=0.08)
>>> u = 1.0 + 2.0 * nodes[:, 0] - nodes[:, 1]          # linear fields are reproduced
>>> bool(np.allclose(table.interpolate(u), u)), bool(np.allclose(table.gradient(u), [2.0, -1.0]))
(True, True)

Methods
-------
The formulas are in ``docs/theory/kernels_and_shape_functions.md`` (its sections in brackets).

``"mls"``         weights ``w_j = W(x - x_j, h_j)`` (classical MLS, Lancaster & Šalkauskas 1981; §2)
``"rkpm"``        weights ``w_j = W(x - x_j, h_j) V_j`` with nodal ``volumes`` (Liu, Jun & Zhang 1995; §3)
``"shepard"``     zeroth order, ``N_j = w_j / Σ w`` (Shepard 1968; §4); optional volumes
``"orthogonal"``  modified Gram–Schmidt basis in the weighted inner product (§5): diagonal
                  moment matrix, no solve; equal to MLS in exact arithmetic; optional volumes
``"singular_shepard"``  interpolating Shepard with the Franke–Little weight
                  ``((R_j - r)/(R_j r))^α``, ``R_j = support * h_j`` (Franke 1982; §4)

Robustness policy
-----------------
At each point the requested order is tried first. If the Cholesky factorisation of the scaled
moment matrix fails, or its 1-norm condition number exceeds ``condition_limit`` (default
``1e8``: reproduction errors then stay below about ``1e-8`` relative), the point falls back to
the next lower order, down to Shepard (order 0), which needs only ``Σ w > 0``. Fallbacks are
flagged per point (``table.fallback``, ``table.order``), counted (``table.n_fallback``) and
reported by a :class:`ShapeFunctionFallbackWarning` (``on_fallback="warn"``; or ``"ignore"``,
``"raise"``). A point without neighbours raises ``ValueError`` naming it. No NaN is returned.
"""

from __future__ import annotations

import logging
import warnings
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.approximation import _compiled
from mlsgalerkin.approximation.table import ShapeTable
from mlsgalerkin.kernels import Kernel, get_kernel
from mlsgalerkin.neighbors import NeighborTable, as_coordinates, find_neighbors
from mlsgalerkin.periodic import as_period
from mlsgalerkin.polynomials import basis_order, basis_size, monomial_exponents

__all__ = [
    "METHODS",
    "ShapeFunctionFallbackWarning",
    "ShapeFunctionFallbackError",
    "shape_functions",
    "evaluate_shape_functions",
]

logger = logging.getLogger(__name__)

METHODS = ("mls", "rkpm", "shepard", "orthogonal", "singular_shepard")
DEFAULT_CONDITION_LIMIT = 1e8


class ShapeFunctionFallbackWarning(UserWarning):
    """Some points fell back to a lower polynomial order (see ``ShapeTable.fallback``)."""


class ShapeFunctionFallbackError(ValueError):
    """Raised instead of the warning when ``on_fallback="raise"``."""


def _positive_array(name: str, a: ArrayLike, n: int) -> NDArray[np.float64]:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have one value per node ({n}), got shape {a.shape}")
    bad = ~(np.isfinite(a) & (a > 0))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{name} must be positive and finite; node {k} has {float(a[k])}")
    return np.ascontiguousarray(a)


def _resolve_order(method: str, basis: str | int | None) -> int:
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if method in ("shepard", "singular_shepard"):
        if basis is not None and basis_order(basis) != 0:
            raise ValueError(f"method={method!r} is zeroth order; use basis='constant' or leave it unset")
        return 0
    return 1 if basis is None else basis_order(basis)


def shape_functions(
    points: ArrayLike,
    nodes: ArrayLike,
    h: ArrayLike,
    kernel: str | Kernel = "cubic_spline",
    basis: str | int | None = None,
    method: str = "mls",
    volumes: ArrayLike | None = None,
    *,
    neighbors: NeighborTable | None = None,
    condition_limit: float = DEFAULT_CONDITION_LIMIT,
    on_fallback: Literal["warn", "ignore", "raise"] = "warn",
    singular_exponent: float = 2.0,
    period: ArrayLike | None = None,
    lower: ArrayLike | None = None,
) -> ShapeTable:
    r"""Shape functions of ``nodes`` and their exact gradients at ``points``.

    Parameters
    ----------
    points : (n_points, dim) float array
        Evaluation points (often the nodes themselves); ``(n,)`` is read as 1D.
    nodes : (n_nodes, dim) float array
    h : float or (n_nodes,) float array
        Dilation (smoothing length) of each node; node ``j`` supports ``|x - x_j| < κ h_j``
        with ``κ = kernel.support``.
    kernel : name or :class:`~mlsgalerkin.kernels.Kernel`
        Must be non-negative (super-Gaussian and new quartic are rejected).
    basis : ``"constant"``, ``"linear"`` or ``"quadratic"``
        Default ``"linear"`` (``"constant"`` for the Shepard methods).
    method : ``"mls"``, ``"rkpm"``, ``"shepard"``, ``"orthogonal"`` or ``"singular_shepard"``
    volumes : (n_nodes,) float array, optional
        Nodal volumes ``V_j`` (required by ``"rkpm"``; optional weights for ``"shepard"`` and
        ``"orthogonal"``).
    neighbors : NeighborTable, optional
        A precomputed table of the nodes within ``κ h_j`` of each point (skips the search).
    condition_limit : float
        Largest accepted 1-norm condition number of the scaled moment matrix.
    on_fallback : ``"warn"``, ``"ignore"`` or ``"raise"``
    singular_exponent : float
        Exponent ``α`` of the singular Shepard weight.
    period, lower : optional, one value per axis (m)
        A periodic domain (:mod:`mlsgalerkin.periodic`): the period of each axis (``0``: not
        periodic) and its lower end (default ``0``); points and nodes must lie in
        ``[lower, lower + period)``. Neighbours are found across the seam and every offset
        ``x_j − x`` is its minimum image.

    Returns
    -------
    ShapeTable
    """
    order = _resolve_order(method, basis)
    kern = get_kernel(kernel)
    nodes_a = as_coordinates("nodes", nodes)
    points_a = nodes_a if points is nodes else as_coordinates("points", points, nodes_a.shape[1])
    n_nodes, dim = nodes_a.shape
    h_a = _positive_array("h", h, n_nodes)
    if method != "singular_shepard" and not kern.nonnegative:
        raise ValueError(
            f"kernel {kern.name!r} takes negative values inside its support, so the moment matrix "
            "need not be positive definite; use a non-negative kernel (e.g. 'cubic_spline', "
            "'quintic_spline', 'wendland_c2') for shape functions"
        )
    if method == "rkpm" and volumes is None:
        raise ValueError("method='rkpm' weights each node by its volume: pass volumes=(n_nodes,) array")
    if volumes is not None and method in ("mls", "singular_shepard"):
        raise ValueError(
            f"method={method!r} does not use volumes; use method='rkpm' for volume-weighted MLS"
        )
    vol = _positive_array("volumes", volumes, n_nodes) if volumes is not None else np.ones(1)
    if not condition_limit > 1.0:
        raise ValueError(f"condition_limit must exceed 1, got {condition_limit!r}")
    if on_fallback not in ("warn", "ignore", "raise"):
        raise ValueError(f"on_fallback must be 'warn', 'ignore' or 'raise', got {on_fallback!r}")

    period_a = as_period(period)
    if neighbors is None:
        neighbors = find_neighbors(points_a, nodes_a, node_radius=kern.support * h_a, period=period, lower=lower)
    elif neighbors.n_points != points_a.shape[0] or neighbors.n_nodes != n_nodes:
        raise ValueError(
            f"neighbors table is {neighbors.n_points} points x {neighbors.n_nodes} nodes, "
            f"expected {points_a.shape[0]} x {n_nodes}"
        )
    _check_isolated(points_a, neighbors)

    table = evaluate_shape_functions(
        points_a, nodes_a, h_a, neighbors, kern, order, method,
        vol if volumes is not None else None, condition_limit, singular_exponent, period=period_a,
    )
    _report_fallbacks(table, on_fallback)
    return table


def _check_isolated(points: NDArray, neighbors: NeighborTable) -> None:
    empty = np.flatnonzero(neighbors.indptr[1:] == neighbors.indptr[:-1])
    if empty.size:
        k = int(empty[0])
        raise ValueError(
            f"{empty.size} evaluation point(s) have no node within the support, first point {k} "
            f"at {points[k].tolist()}; increase h or add nodes near it"
        )


def evaluate_shape_functions(
    points: NDArray[np.float64],
    nodes: NDArray[np.float64],
    h: NDArray[np.float64],
    neighbors: NeighborTable,
    kernel: str | Kernel,
    order: int | str,
    method: str = "mls",
    volumes: NDArray[np.float64] | None = None,
    condition_limit: float = DEFAULT_CONDITION_LIMIT,
    singular_exponent: float = 2.0,
    *,
    fast: bool = True,
    out: ShapeTable | None = None,
    period: NDArray[np.float64] | None = None,
    kernel_sum_volumes: NDArray[np.float64] | None = None,
) -> ShapeTable:
    """Compiled evaluation on validated arrays (no input checks; for solvers and benchmarks).

    ``points (n, dim)``, ``nodes (m, dim)``, ``h (m,)`` and ``volumes (m,)`` must be C-contiguous
    float64. ``kernel`` is a name or a :class:`Kernel`; ``order`` an integer or a basis name.
    ``fast=False`` forces the general path where the fused 2D-linear path applies.

    ``out``: a table from an earlier call whose pair buffers (``values``, ``gradients``) are
    reused when they have the right size — what a time-stepping solver does every step, saving
    the first-touch page faults of fresh arrays (~0.1 s per 10⁶ points in 2D). The earlier
    table's arrays are overwritten: do not keep using it. Its node columns
    (:meth:`ShapeTable.node_columns`) carry over when the neighbour arrays are the same.

    ``period (3,)`` (m): the periods of a periodic domain's axes (``0``: not periodic); the
    offsets ``x_j − x`` are then minimum images (:mod:`mlsgalerkin.periodic`). Default none.

    ``kernel_sum_volumes (m,)`` (m^d): also fill the table's ``kernel_sum`` (the Shepard sum
    ``Σ_j W(x_i − x_j, h_j) V_j`` of each point, dimensionless) and ``kernel_sum_gradient`` (1/m)
    with these node volumes, in the same pass (MLS and RKPM; not the singular Shepard method).
    """
    period = as_period(period)
    kernel = get_kernel(kernel)
    order = basis_order(order)
    dim = points.shape[1]
    n_pairs = neighbors.n_pairs
    if out is not None and out.values.shape[0] >= n_pairs and out.gradients.shape[1] == dim:
        values = out.meta.get("values_buffer", out.values)[:n_pairs]
        grads = out.meta.get("gradients_buffer", out.gradients)[:n_pairs]
        buffers = {"values_buffer": out.meta.get("values_buffer", out.values),
                   "gradients_buffer": out.meta.get("gradients_buffer", out.gradients)}
    else:
        values = np.empty(n_pairs)
        grads = np.empty((n_pairs, dim))
        buffers = {}
    order_out = np.empty(points.shape[0], dtype=np.int64)
    cond = np.ones(points.shape[0])
    indptr, indices = neighbors.indptr, neighbors.indices
    if out is not None and "node_columns" in out.meta:  # kept while the neighbour arrays are the same
        buffers["node_columns"] = out.meta["node_columns"]
    use_vol = volumes is not None
    vol = volumes if use_vol else np.ones(1)
    use_sum = kernel_sum_volumes is not None and method != "singular_shepard"
    if use_sum:
        # the kernels multiply their weights w_j = f(r/h_j) / h_j^d (times vol_j for RKPM) by
        # sum_scale_j: the kernel's normalisation times V_j (divided by vol_j for RKPM)
        v = kernel_sum_volumes / volumes if use_vol else kernel_sum_volumes
        sum_scale = np.ascontiguousarray(float(kernel.normalisation(dim)) * v, dtype=np.float64)
        ksum, ksum_grad = np.empty(points.shape[0]), np.empty((points.shape[0], dim))
    else:
        sum_scale, ksum, ksum_grad = np.ones(1), np.empty(0), np.empty((0, dim))
    sum_args = (use_sum, sum_scale, ksum, ksum_grad)
    if method == "singular_shepard":
        _compiled.singular_shepard_kernel(
            points, nodes, kernel.support * h, indptr, indices, float(singular_exponent),
            values, grads, order_out, period,
        )
    else:
        inv_hd = h ** (-float(dim))
        args = (points, nodes, h, inv_hd, vol, use_vol, kernel.kernel_id, kernel.support, indptr, indices)
        if fast and dim == 2 and order == 1 and method in ("mls", "rkpm"):
            _compiled.linear2d_shape_kernel(*args, float(condition_limit), values, grads, order_out, cond, period,
                                            *sum_args)
        else:
            exps = monomial_exponents(dim, order)
            sizes = np.array([basis_size(dim, o) for o in range(order + 1)], dtype=np.int64)
            _compiled.general_shape_kernel(
                *args, exps, sizes, order, float(condition_limit), method == "orthogonal",
                values, grads, order_out, cond, period, *sum_args,
            )
    failed = np.flatnonzero(order_out < 0)
    if failed.size:
        k = int(failed[0])
        raise ValueError(
            f"{failed.size} point(s) have no usable neighbour (all weights zero), first point {k} "
            f"at {points[k].tolist()}; increase h"
        )
    return ShapeTable(
        points=points, indptr=indptr, indices=indices, values=values, gradients=grads,
        n_nodes=nodes.shape[0], requested_order=order, order=order_out.astype(np.int8),
        condition=cond, method=method, kernel=kernel.name, meta=buffers,
        kernel_sum=ksum if use_sum else None, kernel_sum_gradient=ksum_grad if use_sum else None,
    )


def _report_fallbacks(table: ShapeTable, on_fallback: str) -> None:
    n = table.n_fallback
    if n == 0 or on_fallback == "ignore":
        return
    counts = {o: int(np.count_nonzero(table.order == o)) for o in range(table.requested_order)}
    detail = ", ".join(f"{c} to order {o}" for o, c in counts.items() if c)
    message = (
        f"{n} of {table.n_points} points fell back to a lower order ({detail}): their moment "
        f"matrix was singular or had condition number above the limit; see table.fallback, "
        f"table.order and table.condition"
    )
    logger.debug(message)  # the warning below is the user-facing channel (shown once)
    if on_fallback == "raise":
        raise ShapeFunctionFallbackError(message)
    warnings.warn(message, ShapeFunctionFallbackWarning, stacklevel=3)
