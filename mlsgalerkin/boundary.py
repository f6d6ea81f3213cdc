r"""Boundary quadrature, essential BCs (Nitsche, penalty) and Neumann loads for meshfree bases.

MLS/RKPM shape functions are not interpolating (``N_J(x_I) ≠ δ_IJ``), so prescribed values can
not be set on DOFs as in finite elements (seed digest §4.2). They are imposed weakly on
boundary Gauss points instead.

Boundary quadrature
-------------------
:func:`boundary_basis` returns a :class:`BoundaryBasis` (the meshfree ``FacetBasis``): Gauss
points, weights and outward unit normals on the edges of a convex polygon, with shape values
and **direct** gradients there. The forms of :mod:`mlsgalerkin.forms` assemble on it, with
``w.n`` the normal ``(dim, e)`` and ``w.h`` a local nodal spacing.

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

Nitsche's method (symmetric)
----------------------------
For ``-∇·F(u) = f`` with flux ``F`` (``∇u`` for Poisson, ``σ(u)`` for elasticity) and
``u = g`` on ``Γ_D``:

.. math::

    a(u, v) + \int_{Γ_D}\Big[-(F(u)n)\cdot v - (F(v)n)\cdot u + \frac{βM}{h}\,u\cdot v\Big]dΓ
    = l(v) + \int_{Γ_D}\Big[-(F(v)n)\cdot g + \frac{βM}{h}\,g\cdot v\Big]dΓ .

It is variationally consistent (the exact solution satisfies it), symmetric, and coercive when
``β > 2 C_I``, with ``C_I`` the inverse-estimate constant in ``h ||F(v)n||²_Γ ≤ C_I M a(v, v)``.

Choice of the penalty ``β M / h`` (``nitsche``): ``M`` (``modulus``) is the material scale
(1 or the conductivity for Poisson; ``E`` for elasticity), so that the penalty term has the
units of the consistency terms (modulus / length); ``h`` is a local nodal spacing, so the
parameter does not need retuning under refinement. ``β = 100`` (dimensionless) is the default.

``β > 2 C_I`` is sufficient for coercivity; :func:`nitsche_inverse_constant` measures ``C_I``.
Measured (unit square, cubic spline, linear MLS, dilation 1.5 Δx; elasticity with ``M = E``,
ν = 0.3), for ``n x n`` nodes:

=====================================  =========  =========  =========  ==========
boundary gradients, nodes               n = 7      n = 11     n = 21     n = 41
=====================================  =========  =========  =========  ==========
direct, regular (Poisson / elastic)     12 / 15    12 / 17    11 / 18
direct, perturbed ±0.3 Δx               9 / 13     15 / 24    23 / 41    – / 64
rule (SCNI smoothed), any of the above  1.4–1.6 / 1.9–2.2 (flat in n and dilation)
=====================================  =========  =========  =========  ==========

With direct gradients ``C_I`` also grows with the dilation (Poisson, 7 x 7 perturbed: 9, 27,
71 for 1.5, 2, 2.5 Δx) and with ν (λ dominates σ: use ``M = λ + 2μ`` near incompressibility),
because SCNI's smoothed domain energy does not control pointwise direct gradients on the
boundary. The bound is only sufficient: at 41 x 41 perturbed nodes (``2 C_I = 127 > β``) the
elastic system with ``β = 100`` is still positive definite, with the same lowest eigenvalues as
with ``gradients="rule"``. ``gradients="rule"`` (see :func:`boundary_basis`) makes ``β = 100``
safe with a margin of ~25 whatever the dilation or refinement, and keeps the patch test exact.
Nitsche's error is insensitive to ``β`` once stable; the conditioning grows linearly with it.

Penalty method
--------------
``(βM/h)∫u·v`` and ``(βM/h)∫g·v`` only: simple and symmetric but not consistent (the flux
terms are missing), so the error is ``O(1/β)`` and never reaches round-off, even for a linear
solution: in the SCNI Poisson patch test (9 x 9 perturbed nodes) the relative L2 error is
1.3e-3, 1.4e-4, 2.2e-5 for ``β`` = 1e2, 1e3, 1e4 and then stalls around 1e-6 (``β`` = 1e5 to
1e8) because the conditioning grows like ``β``. Default ``β = 1e4``: close to the end of the
``1/β`` range, without ruining the conditioning.

``w.h`` on a boundary point is ``sqrt(A)`` of the clipped Voronoi cell of the nearest node
(a local nodal spacing, robust to short cell edges near corners).
"""

from __future__ import annotations

import logging
from typing import Any, Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.approximation import ShapeTable
from mlsgalerkin.basis import MeshfreeBasis
from mlsgalerkin.forms import BilinearForm, LinearForm
from mlsgalerkin.helpers import dot, grad, mul
from mlsgalerkin.integration import NodalIntegration, clipped_voronoi_cells, polygon_area
from mlsgalerkin.integration.voronoi import check_domain

__all__ = [
    "BoundaryBasis",
    "boundary_basis",
    "nitsche",
    "nitsche_inverse_constant",
    "penalty",
    "neumann_load",
    "SEGMENTATIONS",
]

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
        refinement, see the module docstring), ``"direct"`` otherwise.
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


# --------------------------------------------------------------------------------------
# prescribed data at boundary points
# --------------------------------------------------------------------------------------


def _boundary_values(boundary: BoundaryBasis, g: Any, name: str) -> FloatArray:
    """``g`` as per-point values ``(n,)`` (scalar basis) or ``(c, n)`` (vector basis)."""
    n, c = boundary.n_points, boundary.n_components
    want = (n,) if c == 1 else (c, n)
    if g is None:
        return np.zeros(want)
    a = np.asarray(g(boundary.points.T), dtype=float) if callable(g) else np.asarray(g, dtype=float)
    if a.shape == want:
        return a
    if a.ndim == 0 or (c > 1 and a.shape == (c,)):
        return np.broadcast_to(a[..., None] if a.ndim else a, want).copy()
    raise ValueError(
        f"{name} must be a constant, a callable x (dim, n) -> {want}, or per-point values of shape "
        f"{want} at the {n} boundary points; got shape {a.shape}"
    )


def _check_boundary(boundary: Any) -> BoundaryBasis:
    if not isinstance(boundary, BoundaryBasis):
        raise ValueError(
            f"expected a BoundaryBasis from boundary_basis(), got {type(boundary).__name__}"
        )
    return boundary


def _mask(boundary: BoundaryBasis, components: Sequence[int] | None) -> FloatArray | None:
    """Component mask ``(c, 1)`` for vector bases (None: all components / scalar basis)."""
    if components is None:
        return None
    c = boundary.n_components
    if c == 1:
        raise ValueError("components= only applies to vector bases")
    comps = [int(i) for i in np.atleast_1d(components)]
    if not comps or any(not 0 <= i < c for i in comps):
        raise ValueError(f"components must be indices in 0..{c - 1}, got {list(components)}")
    m = np.zeros((c, 1))
    m[comps] = 1.0
    return m


def _coefficient(name: str, value: float) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be positive and finite, got {value}")
    return value


def _normal_flux(F: FloatArray, n: FloatArray) -> FloatArray:
    """``F n``: ``(dim, e)`` flux -> ``(e,)``; ``(c, dim, e)`` stress -> ``(c, e)``."""
    if F.ndim == n.ndim:
        return dot(F, n)
    if F.ndim == n.ndim + 1:
        return mul(F, n)
    raise ValueError(f"flux has shape {F.shape}; expected (dim, e) or (c, dim, e)")


def _inner(a: FloatArray, b: FloatArray) -> FloatArray:
    return a * b if a.ndim == 1 else dot(a, b)


# --------------------------------------------------------------------------------------
# essential and natural boundary conditions
# --------------------------------------------------------------------------------------


def nitsche(
    boundary: BoundaryBasis,
    g: Any = None,
    *,
    flux: Callable | None = None,
    modulus: float = 1.0,
    beta: float = 100.0,
    components: Sequence[int] | None = None,
):
    r"""Symmetric Nitsche terms for ``u = g`` on the points of ``boundary``.

    Parameters
    ----------
    boundary : BoundaryBasis
    g : None, constant, callable ``x (dim, n) -> (n,)`` / ``(c, n)``, or per-point values
        Prescribed value (None: homogeneous).
    flux : callable ``u -> F(u)``
        ``(dim, e)`` for scalars (default ``∇u``), ``(c, dim, e)`` for vectors, e.g.
        :func:`mlsgalerkin.models.elasticity.stress` ``(lam, mu)``.
    modulus : float
        Material scale ``M`` of the penalty ``β M / h`` (``E`` for elasticity).
    beta : float
        Dimensionless Nitsche parameter (default 100; see the module docstring).
    components : sequence of int, optional
        Vector bases: constrain only these components (e.g. ``[0]`` for ``u_x = g_x``); the
        others keep their natural condition.

    Returns
    -------
    K : scipy.sparse.csr_array ``(n_dofs, n_dofs)``, symmetric; add to the stiffness matrix.
    f : (n_dofs,) float array; add to the load vector.
    """
    b = _check_boundary(boundary)
    beta = _coefficient("beta", beta)
    modulus = _coefficient("modulus", modulus)
    if flux is None:
        if b.is_vector:
            raise ValueError("vector bases need flux=, e.g. flux=elasticity.stress(lam, mu)")
        flux = grad
    P = _mask(b, components)
    gv = _boundary_values(b, g, "g")
    pen = beta * modulus

    def proj(a):
        return a if P is None else P * a

    def nitsche_lhs(u, v, w):
        Pu, Pv = proj(np.asarray(u)), proj(np.asarray(v))
        return (-_inner(_normal_flux(flux(u), w.n), Pv) - _inner(_normal_flux(flux(v), w.n), Pu)
                + pen / w.h * _inner(Pu, Pv))

    def nitsche_rhs(v, w):
        Pg, Pv = proj(w.g), proj(np.asarray(v))
        return -_inner(_normal_flux(flux(v), w.n), Pg) + pen / w.h * _inner(Pg, Pv)

    return BilinearForm(nitsche_lhs).assemble(b), LinearForm(nitsche_rhs).assemble(b, g=gv)


def nitsche_inverse_constant(
    boundary: BoundaryBasis,
    stiffness: Any,
    *,
    flux: Callable | None = None,
    modulus: float = 1.0,
) -> float:
    r"""Measured inverse-estimate constant ``C_I = max_v (h/M)‖F(v)n‖²_Γ / a(v, v)`` (dense; small problems).

    Symmetric Nitsche is coercive for ``β > 2 C_I`` (Young's inequality on the flux terms).
    ``C_I`` depends on the dilation in units of the nodal spacing, the kernel, the rule and the
    boundary gradients; on regular nodes not on the refinement level, on perturbed nodes with
    direct gradients it grows slowly with the node count (see the module docstring's table).
    ``stiffness`` is the assembled domain matrix ``a`` (its null space, constants or rigid
    motions, carries no flux and is regularised away). Dense generalized eigenproblem: small
    node sets only.
    """
    import scipy.linalg

    b = _check_boundary(boundary)
    modulus = _coefficient("modulus", modulus)
    if flux is None:
        if b.is_vector:
            raise ValueError("vector bases need flux=, e.g. flux=elasticity.stress(lam, mu)")
        flux = grad
    if stiffness.shape != (b.n_dofs, b.n_dofs):
        raise ValueError(f"stiffness must be ({b.n_dofs}, {b.n_dofs}), got {stiffness.shape}")
    if b.n_dofs > 4000:
        raise ValueError(
            f"{b.n_dofs} DOFs is too many for a dense eigenvalue problem; use a coarser node set"
        )

    def flux_flux(u, v, w):
        return w.h / modulus * _inner(_normal_flux(flux(u), w.n), _normal_flux(flux(v), w.n))

    B = BilinearForm(flux_flux).assemble(b).toarray()
    K = stiffness.toarray() if hasattr(stiffness, "toarray") else np.asarray(stiffness, dtype=float)
    K = 0.5 * (K + K.T)
    shift = 1e-10 * float(np.abs(K).max())
    n = b.n_dofs
    top = scipy.linalg.eigh(B, K + shift * np.eye(n), eigvals_only=True,
                            subset_by_index=[n - 1, n - 1])
    return float(top[0])


def penalty(
    boundary: BoundaryBasis,
    g: Any = None,
    *,
    modulus: float = 1.0,
    beta: float = 1e4,
    components: Sequence[int] | None = None,
):
    r"""Penalty terms ``(βM/h)∫u·v`` and ``(βM/h)∫g·v`` for ``u = g`` (not consistent: error ``O(1/β)``).

    Arguments as :func:`nitsche`; returns ``(K, f)`` to add to the system.
    """
    b = _check_boundary(boundary)
    beta = _coefficient("beta", beta)
    modulus = _coefficient("modulus", modulus)
    P = _mask(b, components)
    gv = _boundary_values(b, g, "g")
    pen = beta * modulus

    def proj(a):
        return a if P is None else P * a

    def penalty_lhs(u, v, w):
        return pen / w.h * _inner(proj(np.asarray(u)), proj(np.asarray(v)))

    def penalty_rhs(v, w):
        return pen / w.h * _inner(proj(w.g), proj(np.asarray(v)))

    return BilinearForm(penalty_lhs).assemble(b), LinearForm(penalty_rhs).assemble(b, g=gv)


def neumann_load(boundary: BoundaryBasis, t: Any) -> FloatArray:
    r"""Natural-boundary load ``∫_Γ t·v dΓ``: traction ``t`` (N/m², vector) or flux ``q`` (scalar).

    ``t``: constant, callable ``x (dim, n) -> (n,)`` / ``(c, n)``, or per-point values. Use the
    same ``segments="cells"`` quadrature as the SCNI rule for exact patch tests.
    """
    b = _check_boundary(boundary)
    tv = _boundary_values(b, t, "t")

    def neumann(v, w):
        return _inner(w.t, np.asarray(v))

    return LinearForm(neumann).assemble(b, t=tv)
