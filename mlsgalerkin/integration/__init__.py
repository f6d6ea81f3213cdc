"""Nodal integration rules (DNI, SCNI), nodal volumes from Voronoi cells, boundary quadrature."""

from mlsgalerkin.integration.boundary import BoundaryBasis, boundary_basis
from mlsgalerkin.integration.nodal_basis import meshfree_basis
from mlsgalerkin.integration.rules import (
    NodalIntegration,
    direct_nodal_integration,
    stabilized_conforming_nodal_integration,
)
from mlsgalerkin.integration.voronoi import (
    clipped_voronoi_cells,
    polygon_area,
    rectangle,
    voronoi_volumes,
)

__all__ = [
    "BoundaryBasis",
    "NodalIntegration",
    "boundary_basis",
    "clipped_voronoi_cells",
    "direct_nodal_integration",
    "meshfree_basis",
    "polygon_area",
    "rectangle",
    "stabilized_conforming_nodal_integration",
    "voronoi_volumes",
]
