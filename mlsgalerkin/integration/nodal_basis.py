"""A :class:`~mlsgalerkin.basis.MeshfreeBasis` on a nodal integration rule chosen by name.

:func:`meshfree_basis` builds the rule (:func:`~mlsgalerkin.integration.direct_nodal_integration`
or :func:`~mlsgalerkin.integration.stabilized_conforming_nodal_integration`: points ``(n, dim)``,
weights ``(n,)`` in length^dim, shape table) and wraps it in the basis the forms assemble against.

>>> import numpy as np
>>> from mlsgalerkin.integration import meshfree_basis, rectangle
>>> g = np.stack(np.meshgrid(*[np.linspace(0, 1, 6)] * 2, indexing="ij"), -1).reshape(-1, 2)
>>> dni = meshfree_basis(g, h=0.3, rule="dni", domain=rectangle((0, 0), (1, 1)))
>>> dni.name, dni.n_dofs, round(float(dni.weights.sum()), 12)     # Voronoi volumes: area 1
('DNI', 36, 1.0)
"""

from __future__ import annotations

import logging
from typing import Any

from numpy.typing import ArrayLike

from mlsgalerkin.basis import MeshfreeBasis
from mlsgalerkin.integration.rules import (
    direct_nodal_integration,
    stabilized_conforming_nodal_integration,
)
from mlsgalerkin.integration.voronoi import voronoi_volumes
from mlsgalerkin.neighbors import as_coordinates

__all__ = ["meshfree_basis", "RULES"]

logger = logging.getLogger(__name__)

RULES = ("scni", "dni")


def meshfree_basis(
    nodes: ArrayLike,
    h: ArrayLike,
    *,
    rule: str = "scni",
    domain: ArrayLike | None = None,
    volumes: ArrayLike | None = None,
    n_components: int = 1,
    n_gauss: int = 2,
    **shape_kw: Any,
) -> MeshfreeBasis:
    """Build a nodal integration rule and wrap it in a :class:`MeshfreeBasis` (2D for SCNI).

    Parameters
    ----------
    nodes : (n_nodes, dim) float array
    h : float or (n_nodes,) float array
        Dilation; node ``I`` supports ``|x - x_I| < κ h_I`` (κ = kernel support, 2 for the
        cubic spline).
    rule : ``"scni"`` or ``"dni"``
    domain : (n_corners, 2) float array
        Convex counter-clockwise polygon (e.g. :func:`~mlsgalerkin.integration.rectangle`).
        Required for SCNI, and for DNI unless ``volumes`` is given.
    volumes : (n_nodes,) float array, optional
        DNI weights; default the clipped Voronoi cell areas.
    n_components : 1 or dim
    n_gauss : int
        Gauss points per SCNI cell edge.
    **shape_kw
        ``kernel``, ``basis``, ``method``, ... of :func:`~mlsgalerkin.shape_functions`.
    """
    key = str(rule).lower()
    if key not in RULES:
        raise ValueError(f"unknown integration rule {rule!r}; choose one of {', '.join(RULES)}")
    x = as_coordinates("nodes", nodes)
    if key == "scni":
        if domain is None:
            raise ValueError("rule='scni' needs the domain polygon (e.g. rectangle(lower, upper))")
        r = stabilized_conforming_nodal_integration(x, h, domain, n_gauss=n_gauss, **shape_kw)
    else:
        if volumes is None:
            if domain is None:
                raise ValueError("rule='dni' needs volumes or a domain to compute Voronoi volumes")
            volumes = voronoi_volumes(x, domain)
        r = direct_nodal_integration(x, h, volumes, **shape_kw)
    kw = {"kernel": r.table.kernel, "basis": r.table.requested_order, "method": r.table.method}
    kw.update(shape_kw)
    logger.debug("built %s basis on %d nodes (%d pairs)", r.name, x.shape[0], r.table.n_pairs)
    return MeshfreeBasis(x, r, n_components, h=h, shape_kw=kw)
