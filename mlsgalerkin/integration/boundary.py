r"""Boundary quadrature for meshfree bases: :class:`BoundaryBasis`, the meshfree ``FacetBasis``.

:func:`boundary_basis` returns a :class:`BoundaryBasis`: Gauss points, weights and outward unit
normals on the edges of a convex polygon, with shape values and gradients there (``gradients=``:
the direct ones, or the domain rule's). The forms of :mod:`mlsgalerkin.forms` assemble on it,
with ``w.n`` the normal ``(dim, e)`` and ``w.h`` a local nodal spacing; the weak boundary
conditions and loads of :mod:`mlsgalerkin.models.boundary_conditions` are built on it.

Two segmentations of each domain edge:

``segments="cells"`` (default)
    The boundary edges of the nodes' clipped Voronoi cells, with the same Gauss points as
    :func:`~mlsgalerkin.integration.stabilized_conforming_nodal_integration` (``n_gauss``
    defaults to the SCNI rule's). SCNI's smoothed gradients satisfy the integration constraint
    ``Σ_L A_L ∇̃N_I(x_L) = Σ_g N_I(x_g) n_g w_g`` *with these very boundary points*; boundary
    terms on the same points cancel the domain term exactly for a linear solution, so the
    linear patch test passes to round-off. Any other boundary rule leaves a quadrature-sized
    residual.
``segments="nodes"``
    Segments between consecutive boundary nodes (and corners).

``w.h`` on a boundary point is ``sqrt(A)`` of the clipped Voronoi cell of the nearest node
(a local nodal spacing, robust to short cell edges near corners).
"""

from __future__ import annotations

import logging
from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.approximation import ShapeTable
from mlsgalerkin.basis import MeshfreeBasis
from mlsgalerkin.integration.rules import NodalIntegration
from mlsgalerkin.integration.voronoi import check_domain, clipped_voronoi_cells, polygon_area

__all__ = ["BoundaryBasis", "boundary_basis", "SEGMENTATIONS", "GRADIENTS"]

logger = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
SEGMENTATIONS = ("cells", "nodes")
GRADIENTS = ("direct", "rule")


class BoundaryBasis(MeshfreeBasis):
    """A :class:`MeshfreeBasis` on boundary Gauss points, with outward normals.

    Extra attributes
    ----------------
    normals : (n_points, dim) float array, unit outward normals
    edge : (n_points,) int array, domain edge of each point (edge ``k`` runs from corner ``k``
        to corner ``k + 1``)
    spacing : (n_points,) float array, local nodal spacing ``h`` (length) used by penalties
    """

    def __init__(self, nodes: ArrayLike, rule: Any, n_components: int = 1, *, normals: ArrayLike,
                 edge: ArrayLike, spacing: ArrayLike, h: ArrayLike | None = None,
                 shape_kw: dict | None = None) -> None:
        super().__init__(nodes, rule, n_components, h=h, shape_kw=shape_kw)
        self.normals = np.asarray(normals, dtype=np.float64)
        self.edge = np.asarray(edge, dtype=np.int64)
        self.spacing = np.asarray(spacing, dtype=np.float64)
        n = self.n_points
        if (self.normals.shape != (n, self.dim) or self.edge.shape != (n,)
                or self.spacing.shape != (n,)):
            raise ValueError("normals (n, dim), edge (n,) and spacing (n,) must match the points")

    def default_parameters(self) -> dict[str, FloatArray]:
        """``x (dim, n)``, ``h (n,)`` (local nodal spacing) and ``n (dim, n)`` outward normals."""
        return {"x": self.points.T, "h": self.spacing, "n": self.normals.T}

    @property
    def length(self) -> float:
        """Total length of the boundary part covered (sum of weights)."""
        return float(self.weights.sum())


def _gauss_on_segments(a: FloatArray, b: FloatArray, n_gauss: int):
    """Gauss points ``a + t (b - a)`` and weights ``½ w_g |b - a|`` (ordering: segment-major)."""
    xg, wg = np.polynomial.legendre.leggauss(n_gauss)
    t = 0.5 * (xg + 1.0)
    e = b - a
    length = np.linalg.norm(e, axis=1)
    pts = np.concatenate([a + tg * e for tg in t])
    wts = np.concatenate([0.5 * w * length for w in wg])
    return pts, wts, np.tile(np.arange(a.shape[0]), n_gauss)


def _cell_segments(cells: list[FloatArray], dom: FloatArray, edges: Sequence[int], tol: float):
    """Boundary edges of the clipped cells lying on each selected domain edge."""
    verts = np.concatenate(cells)
    sizes = np.array([c.shape[0] for c in cells])
    starts = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    nxt = np.arange(verts.shape[0]) + 1
    nxt[starts + sizes - 1] = starts
    a, b = verts, verts[nxt]
    e = b - a
    keep = np.linalg.norm(e, axis=1) > 0  # the SCNI rule's own criterion
    out_a, out_b, out_k = [], [], []
    m = dom.shape[0]
    for k in edges:
        p0, p1 = dom[k], dom[(k + 1) % m]
        t = (p1 - p0) / np.linalg.norm(p1 - p0)
        nrm = np.array([t[1], -t[0]])
        on = keep & (np.abs((a - p0) @ nrm) < tol) & (np.abs((b - p0) @ nrm) < tol) & (e @ t > 0)
        out_a.append(a[on])
        out_b.append(b[on])
        out_k.append(np.full(int(on.sum()), k))
    return np.concatenate(out_a), np.concatenate(out_b), np.concatenate(out_k)


def _node_segments(nodes: FloatArray, dom: FloatArray, edges: Sequence[int], tol: float):
    """Segments between consecutive nodes lying on each selected domain edge (and corners)."""
    out_a, out_b, out_k = [], [], []
    m = dom.shape[0]
    for k in edges:
        p0, p1 = dom[k], dom[(k + 1) % m]
        L = float(np.linalg.norm(p1 - p0))
        t = (p1 - p0) / L
        nrm = np.array([t[1], -t[0]])
        s = (nodes - p0) @ t
        on = (np.abs((nodes - p0) @ nrm) < tol) & (s > tol) & (s < L - tol)
        bp = np.unique(np.concatenate(([0.0], s[on], [L])))
        bp = bp[np.concatenate(([True], np.diff(bp) > tol))]
        bp[-1] = L
        out_a.append(p0 + bp[:-1, None] * t)
        out_b.append(p0 + bp[1:, None] * t)
        out_k.append(np.full(bp.size - 1, k))
    return np.concatenate(out_a), np.concatenate(out_b), np.concatenate(out_k)


def _with_rule_gradients(values: ShapeTable, rule_table: ShapeTable, owner: NDArray) -> ShapeTable:
    """A table with ``values``' shape values and the rule table's gradients at ``owner`` points."""
    from scipy.sparse import csr_array

    n_q = values.n_points
    R = csr_array((np.ones(n_q), (np.arange(n_q), owner)), shape=(n_q, rule_table.n_points))
    grads = [csr_array(R @ G) for G in rule_table.gradient_matrices()]
    V = values.value_matrix()
    pattern = abs(V) + sum(abs(G) for G in grads)  # union of the sparsity patterns
    pattern = csr_array(pattern)
    pattern.sort_indices()
    rows = np.repeat(np.arange(n_q), np.diff(pattern.indptr))
    cols = pattern.indices

    def on_pattern(A) -> FloatArray:
        return np.asarray(A[rows, cols]).ravel()

    return ShapeTable(
        points=values.points, indptr=pattern.indptr.astype(np.int64), indices=cols.astype(np.int32),
        values=on_pattern(V), gradients=np.column_stack([on_pattern(G) for G in grads]),
        n_nodes=values.n_nodes, requested_order=values.requested_order,
        order=np.minimum(values.order, rule_table.order[owner]), condition=values.condition,
        method=values.method, kernel=values.kernel, meta={"gradients": "rule"},
    )


def boundary_basis(
    basis: MeshfreeBasis,
    domain: ArrayLike,
    *,
    edges: Sequence[int] | None = None,
    segments: str = "cells",
    n_gauss: int | None = None,
    gradients: str | None = None,
) -> BoundaryBasis:
    """Boundary Gauss points of a convex polygonal ``domain`` as a :class:`BoundaryBasis`.

    Parameters
    ----------
    basis : MeshfreeBasis
        The domain basis (its nodes, dilation and shape-function settings are reused; it must
        know ``h``).
    domain : (n_corners, 2) float array
        Convex counter-clockwise polygon (the one the rule was built on).
    edges : sequence of int, optional
        Domain edges to cover (edge ``k`` joins corners ``k`` and ``k + 1``); default all.
        For :func:`~mlsgalerkin.integration.rectangle`: 0 bottom, 1 right, 2 top, 3 left.
    segments : ``"cells"`` or ``"nodes"``
        Segmentation of the edges (see the module docstring; ``"cells"`` makes SCNI pass the
        patch test exactly).
    n_gauss : int, optional
        Gauss points per segment; default the SCNI rule's (``basis.table.meta``), else 2.
    gradients : ``"direct"`` or ``"rule"``, optional
        Default ``"rule"`` for an SCNI basis (``β = 100`` is then safe at any dilation and
        refinement, see :mod:`mlsgalerkin.models.boundary_conditions`), ``"direct"`` otherwise.
        ``"direct"``: exact gradients of the shape functions at the boundary points.
        ``"rule"``: the domain rule's gradient at the integration point nearest to each
        boundary point, i.e. the smoothed gradient of the SCNI cell the boundary edge belongs
        to. Both reproduce linear fields (patch tests stay exact); ``"rule"`` makes the
        Nitsche flux terms consistent with the SCNI domain energy, so the inverse constant
        ``C_I`` (and the ``β`` needed for coercivity) no longer grows with the dilation.
    """
    if not isinstance(basis, MeshfreeBasis):
        raise ValueError(f"basis must be a MeshfreeBasis, got {type(basis).__name__}")
    if basis.dim != 2:
        raise ValueError(
            f"boundary quadrature is implemented for 2D polygons; basis is {basis.dim}D"
        )
    if segments not in SEGMENTATIONS:
        raise ValueError(f"unknown segments {segments!r}; choose one of {', '.join(SEGMENTATIONS)}")
    dom = check_domain(domain)
    m = dom.shape[0]
    if edges is None:
        edges = list(range(m))
    else:
        edges = [int(k) for k in np.atleast_1d(edges)]
        bad = [k for k in edges if not 0 <= k < m]
        if bad or len(set(edges)) != len(edges):
            raise ValueError(f"edges must be distinct indices in 0..{m - 1}, got {edges}")
    rule_gauss = basis.table.meta.get("n_gauss")
    if n_gauss is None:
        n_gauss = int(rule_gauss) if rule_gauss is not None else 2
    if int(n_gauss) < 1:
        raise ValueError(f"n_gauss must be >= 1, got {n_gauss}")
    if gradients is None:
        gradients = "rule" if basis.name == "SCNI" else "direct"
    if gradients not in GRADIENTS:
        raise ValueError(f"unknown gradients {gradients!r}; choose one of {', '.join(GRADIENTS)}")
    if basis.name == "SCNI" and (segments != "cells" or n_gauss != rule_gauss):
        logger.warning(
            "boundary quadrature (segments=%r, n_gauss=%d) is not the SCNI rule's own "
            "(segments='cells', n_gauss=%s): boundary and domain terms will not cancel exactly "
            "in patch tests", segments, n_gauss, rule_gauss)
    tol = 1e-10 * float(np.ptp(dom, axis=0).max())
    cells = clipped_voronoi_cells(basis.nodes, dom)
    if segments == "cells":
        a, b, k = _cell_segments(cells, dom, edges, tol)
    else:
        a, b, k = _node_segments(basis.nodes, dom, edges, tol)
    if a.shape[0] == 0:
        raise ValueError(f"no boundary segment found on edges {edges}")
    points, weights, seg = _gauss_on_segments(a, b, int(n_gauss))
    edge_of_point = k[seg]
    corner = dom[edge_of_point]
    tvec = dom[(edge_of_point + 1) % m] - corner
    tvec /= np.linalg.norm(tvec, axis=1, keepdims=True)
    normals = np.column_stack([tvec[:, 1], -tvec[:, 0]])

    from scipy.spatial import cKDTree

    area = np.array([polygon_area(c) for c in cells])
    _, nearest = cKDTree(basis.nodes).query(points)
    spacing = np.sqrt(area[nearest])
    table = basis.shape_functions_at(points)
    if gradients == "rule":
        _, owner = cKDTree(basis.points).query(points)
        table = _with_rule_gradients(table, basis.table, owner)
    rule = NodalIntegration("boundary", points, weights, table)
    logger.debug("boundary quadrature: %d segments, %d points, length %.6g", a.shape[0],
                 points.shape[0], weights.sum())
    return BoundaryBasis(basis.nodes, rule, basis.n_components, normals=normals, edge=edge_of_point,
                         spacing=spacing, h=basis.h, shape_kw=basis.shape_kw)
