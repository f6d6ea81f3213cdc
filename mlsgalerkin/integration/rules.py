r"""Nodal integration rules: direct (DNI) and stabilised conforming (SCNI).

Both integrate at the nodes with weights ``w_L`` (nodal volumes) and return a
:class:`NodalIntegration`: the points, the weights and a :class:`ShapeTable` whose ``values``
are ``N_I(x_L)`` and whose ``gradients`` are what the rule uses for ``∇N_I`` at ``x_L``.

DNI
    ``∇N_I(x_L)`` evaluated directly (the choice of Cueto-Felgueroso et al. 2005). Cheap; fails the
    linear patch test on irregular nodes and admits spurious zero-energy modes.

SCNI (Chen, Wu, Yoon & You 2001)
    Gradients smoothed over the node's Voronoi cell ``Ω_L`` (area ``A_L``) by the divergence
    theorem,

    .. math:: \tilde{\nabla} N_I(\mathbf x_L) = \frac{1}{A_L}\int_{\Omega_L} \nabla N_I\,d\Omega
              = \frac{1}{A_L}\oint_{\partial\Omega_L} N_I\,\mathbf n\,d\Gamma
              \approx \frac{1}{A_L}\sum_{e}\sum_{g} N_I(\mathbf x_g)\,\mathbf n_e\,w_g |e| .

    Adjacent cells share their edge quadrature points, so the interior contributions cancel
    exactly and the integration constraint ``Σ_L ∇̃N_I(x_L) A_L = ∮_Γ N_I n dΓ`` holds: the
    linear patch test passes to round-off. Gauss–Legendre points on each edge (any number
    ``>= 1`` integrates the linear part exactly).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.approximation import ShapeTable, shape_functions
from mlsgalerkin.integration.voronoi import clipped_voronoi_cells, polygon_area

__all__ = ["NodalIntegration", "direct_nodal_integration", "stabilized_conforming_nodal_integration"]


@dataclass(frozen=True, eq=False)
class NodalIntegration:
    """Integration points (the nodes), weights and the shape table the rule integrates with.

    Attributes
    ----------
    name : ``"DNI"`` or ``"SCNI"``
    points : (n, dim) float array
    weights : (n,) float array, nodal volumes (sum to the domain measure)
    table : ShapeTable, values ``N_I(x_L)`` and the rule's gradients
    """

    name: str
    points: NDArray[np.float64]
    weights: NDArray[np.float64]
    table: ShapeTable


def direct_nodal_integration(
    nodes: ArrayLike, h: ArrayLike, volumes: ArrayLike, **shape_kw
) -> NodalIntegration:
    """DNI: shape functions and their gradients evaluated at the nodes, weights = ``volumes``."""
    x = np.ascontiguousarray(nodes, dtype=float)
    table = shape_functions(x, x, h, **shape_kw)
    return NodalIntegration("DNI", x, np.asarray(volumes, dtype=float), table)


def _edge_quadrature(cells: list[NDArray], n_gauss: int):
    """All edge Gauss points, their owning cell and ``n_e w_g |e|``, ``(n_gp, 2)``."""
    xg, wg = np.polynomial.legendre.leggauss(n_gauss)
    t = 0.5 * (xg + 1.0)
    pts, owner, nw = [], [], []
    for L, poly in enumerate(cells):
        a = poly
        b = np.roll(poly, -1, axis=0)
        e = b - a
        length = np.linalg.norm(e, axis=1)
        normal = np.column_stack([e[:, 1], -e[:, 0]])  # outward for CCW, |normal| = |e|
        keep = length > 0
        a, e, normal = a[keep], e[keep], normal[keep]
        for tg, w in zip(t, wg):
            pts.append(a + tg * e)
            nw.append(0.5 * w * normal)
            owner.append(np.full(a.shape[0], L))
    return np.vstack(pts), np.concatenate(owner), np.vstack(nw)


def stabilized_conforming_nodal_integration(
    nodes: ArrayLike, h: ArrayLike, domain: ArrayLike, *, n_gauss: int = 2, **shape_kw
) -> NodalIntegration:
    """SCNI on the Voronoi cells of ``nodes`` clipped to the convex polygon ``domain`` (2D).

    Returns weights = cell areas and a table with smoothed gradients (see module docstring).
    ``shape_kw`` go to :func:`~mlsgalerkin.shape_functions` (kernel, basis, method, ...).
    """
    from scipy.sparse import csr_array

    x = np.ascontiguousarray(nodes, dtype=float)
    if n_gauss < 1:
        raise ValueError(f"n_gauss must be >= 1, got {n_gauss}")
    cells = clipped_voronoi_cells(x, domain)
    area = np.array([polygon_area(c) for c in cells])
    gp, owner, nw = _edge_quadrature(cells, n_gauss)
    edge_table = shape_functions(gp, x, h, **shape_kw)
    node_table = shape_functions(x, x, h, **shape_kw)
    n = x.shape[0]
    N_edge = edge_table.value_matrix()
    smoothed = []
    for d in range(2):
        C = csr_array((nw[:, d] / area[owner], (owner, np.arange(gp.shape[0]))), shape=(n, gp.shape[0]))
        smoothed.append(csr_array(C @ N_edge))
    # one sparsity pattern for values and both smoothed gradients
    pattern = abs(node_table.value_matrix()) + abs(smoothed[0]) + abs(smoothed[1])
    pattern = csr_array(pattern)
    pattern.sort_indices()
    rows = np.repeat(np.arange(n), np.diff(pattern.indptr))
    cols = pattern.indices

    def on_pattern(A) -> NDArray:
        return np.asarray(A[rows, cols]).ravel()

    table = ShapeTable(
        points=x,
        indptr=pattern.indptr.astype(np.int64),
        indices=cols.astype(np.int32),
        values=on_pattern(node_table.value_matrix()),
        gradients=np.column_stack([on_pattern(smoothed[0]), on_pattern(smoothed[1])]),
        n_nodes=n,
        requested_order=node_table.requested_order,
        order=np.minimum(node_table.order, _min_order_per_cell(edge_table, owner, n)),
        condition=node_table.condition,
        method=node_table.method,
        kernel=node_table.kernel,
        meta={"rule": "SCNI", "n_gauss": n_gauss, "edge_points": gp.shape[0]},
    )
    return NodalIntegration("SCNI", x, area, table)


def _min_order_per_cell(edge_table: ShapeTable, owner: NDArray, n: int) -> NDArray:
    out = np.full(n, 127, dtype=np.int16)
    np.minimum.at(out, owner, edge_table.order.astype(np.int16))
    return out.astype(np.int8)
