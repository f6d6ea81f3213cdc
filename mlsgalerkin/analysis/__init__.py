"""Verification tools: error norms against closed-form solutions and convergence rates."""

from mlsgalerkin.analysis.convergence import (
    ROUNDOFF,
    ObservedOrder,
    PowerLawFit,
    fit_power_law,
    observed_order,
    observed_orders,
)
from mlsgalerkin.analysis.norms import (
    ErrorNorms,
    Quadrature,
    energy_error,
    h1_seminorm_error,
    l2_error,
    rectangle_quadrature,
)

__all__ = [
    "ROUNDOFF",
    "ObservedOrder",
    "PowerLawFit",
    "fit_power_law",
    "observed_order",
    "observed_orders",
    "ErrorNorms",
    "Quadrature",
    "energy_error",
    "h1_seminorm_error",
    "l2_error",
    "rectangle_quadrature",
]
