"""Reusable forms (mirroring :mod:`skfem.models`): Poisson, elasticity, weak boundary conditions."""

from mlsgalerkin.models import boundary_conditions, elasticity, poisson
from mlsgalerkin.models.boundary_conditions import (
    neumann_load,
    nitsche,
    nitsche_inverse_constant,
    penalty,
)

__all__ = [
    "boundary_conditions",
    "elasticity",
    "neumann_load",
    "nitsche",
    "nitsche_inverse_constant",
    "penalty",
    "poisson",
]
