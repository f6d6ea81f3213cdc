"""Reusable forms (mirroring :mod:`skfem.models`): Poisson and linear elasticity."""

from mlsgalerkin.models import elasticity, poisson

__all__ = ["elasticity", "poisson"]
