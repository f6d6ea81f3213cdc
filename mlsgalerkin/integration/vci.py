r"""Variationally consistent integration (VCI) of a direct nodal rule (Chen, Hillman & Rüter 2013).

Direct nodal integration (DNI) fails the linear patch test because its gradients violate the
*integration constraint* (the discrete divergence theorem for each shape function),

.. math:: \sum_L \nabla N_I(\mathbf x_L)\, w_L = \oint_\Gamma N_I\, \mathbf n \, d\Gamma
          \qquad\text{for every node } I .

VCI corrects the **test-function** gradients so that the constraint holds with the boundary
quadrature the boundary terms use,

.. math:: \tilde\nabla N_I(\mathbf x_L) = \nabla N_I(\mathbf x_L)
          + \boldsymbol\xi_I\, c_I(\mathbf x_L),
          \qquad
          \boldsymbol\xi_I = \frac{\oint_\Gamma N_I \mathbf n\,d\Gamma
                                   - \sum_L \nabla N_I(\mathbf x_L) w_L}
                                  {\sum_L c_I(\mathbf x_L)\, w_L},

with one constant vector ``ξ_I`` per node and the correction profile ``c_I = 1`` on the support
of ``N_I`` (``correction="constant"``) or ``c_I = N_I`` (``correction="shape"``, which vanishes
smoothly at the support edge). The trial functions keep their exact gradients, so the linear
field's discrete gradient stays exact and constants (rigid motions) keep zero energy; the
stiffness ``K_IJ = Σ_L w_L a(N_J, Ñ_I)(x_L)`` is therefore **unsymmetric** (Petrov–Galerkin).
With both consistency (trial) and the integration constraint (test) the linear patch test
passes to round-off, provided the Nitsche/traction terms use the same boundary points
(:func:`~mlsgalerkin.integration.boundary_basis` with ``segments="cells"``, the default).

VCI restores consistency, not stability: DNI's spurious low-energy modes remain.

>>> import numpy as np
>>> from mlsgalerkin.integration import meshfree_basis, rectangle
>>> g = np.stack(np.meshgrid(*[np.linspace(0, 1, 6)] * 2, indexing="ij"), -1).reshape(-1, 2)
>>> dom = rectangle((0, 0), (1, 1))
>>> dni = meshfree_basis(g, 0.3, rule="dni", domain=dom)
>>> test = vci_test_basis(dni, dom)
>>> float(integration_constraint_residual(dni, dom).max()) > 1e-3
True
>>> float(integration_constraint_residual(test, dom).max()) < 1e-14
True
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.basis import MeshfreeBasis
from mlsgalerkin.integration.boundary import boundary_basis
from mlsgalerkin.integration.rules import NodalIntegration

__all__ = ["vci_test_basis", "integration_constraint_residual", "CORRECTIONS"]

logger = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
CORRECTIONS = ("constant", "shape")


def _boundary_moments(basis: MeshfreeBasis, domain: ArrayLike, n_gauss: int | None) -> FloatArray:
    """``∮ N_I n dΓ`` per node, ``(n_nodes, dim)``, on the cell-edge boundary quadrature."""
    bb = boundary_basis(basis, domain, segments="cells", n_gauss=n_gauss, gradients="direct")
    N = bb.table.value_matrix()
    return np.column_stack([N.T @ (bb.weights * bb.normals[:, d]) for d in range(basis.dim)])


def _domain_moments(basis: MeshfreeBasis) -> FloatArray:
    """``Σ_L ∇N_I(x_L) w_L`` per node with the rule's gradients, ``(n_nodes, dim)``."""
    return np.column_stack([G.T @ basis.weights for G in basis.table.gradient_matrices()])


def integration_constraint_residual(basis: MeshfreeBasis, domain: ArrayLike, *,
                                    n_gauss: int | None = None) -> FloatArray:
    """Violation of the integration constraint per node, ``(n_nodes,)``, dimensionless.

    ``|Σ_L ∇N_I(x_L) w_L − ∮ N_I n dΓ|`` divided by ``max_I Σ_L |∇N_I(x_L)| w_L``; round-off
    is ~1e-15. The boundary integral uses the cell-edge quadrature of
    :func:`~mlsgalerkin.integration.boundary_basis`.
    """
    b = _boundary_moments(basis, domain, n_gauss)
    a = _domain_moments(basis)
    scale = max(float(np.abs(np.column_stack(
        [abs(G).T @ basis.weights for G in basis.table.gradient_matrices()])).max()), 1e-300)
    return np.linalg.norm(a - b, axis=1) / scale


def vci_test_basis(basis: MeshfreeBasis, domain: ArrayLike, *, correction: str = "constant",
                   n_gauss: int | None = None) -> MeshfreeBasis:
    """Test basis with VCI-corrected gradients of the nodal rule of ``basis`` (usually DNI).

    Parameters
    ----------
    basis : MeshfreeBasis
        Trial basis (same points, weights, values and components are kept). Must know ``h``.
    domain : (n_corners, 2) float array
        Convex counter-clockwise polygon of the rule.
    correction : ``"constant"`` or ``"shape"``
        Profile ``c_I`` of the correction (see the module docstring).
    n_gauss : int, optional
        Gauss points per boundary cell edge (default 2, as
        :func:`~mlsgalerkin.integration.boundary_basis`).

    Returns
    -------
    MeshfreeBasis named ``"VCI"``; assemble with ``form.assemble(basis, test_basis=vci)``.
    """
    if not isinstance(basis, MeshfreeBasis):
        raise ValueError(f"basis must be a MeshfreeBasis, got {type(basis).__name__}")
    if correction not in CORRECTIONS:
        raise ValueError(f"unknown correction {correction!r}; "
                         f"choose one of {', '.join(CORRECTIONS)}")
    T = basis.table
    rows = T.rows()
    w_pair = basis.weights[rows]
    profile = np.ones(T.n_pairs) if correction == "constant" else T.values
    denom = np.bincount(T.indices, weights=profile * w_pair, minlength=T.n_nodes)
    bad = np.flatnonzero(~(np.abs(denom) > 0))
    if bad.size:
        raise ValueError(
            f"{bad.size} node(s) have a zero correction weight Σ_L c_I(x_L) w_L (first node "
            f"{int(bad[0])}): their shape function vanishes at every integration point; "
            f"increase h or use correction='constant'")
    xi = (_boundary_moments(basis, domain, n_gauss) - _domain_moments(basis)) / denom[:, None]
    grads = T.gradients + xi[T.indices] * profile[:, None]
    table = replace(T, gradients=np.ascontiguousarray(grads),
                    meta={**T.meta, "rule": "VCI", "correction": correction})
    logger.debug("VCI: max |ξ_I| = %.3g over %d nodes", float(np.abs(xi).max()), T.n_nodes)
    rule = NodalIntegration("VCI", basis.points, basis.weights, table)
    return MeshfreeBasis(basis.nodes, rule, basis.n_components, h=basis.h, shape_kw=basis.shape_kw)
