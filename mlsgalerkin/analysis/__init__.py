"""Verification tools: error norms against closed-form solutions."""

from mlsgalerkin.analysis.norms import (
    ErrorNorms,
    Quadrature,
    energy_error,
    h1_seminorm_error,
    l2_error,
    rectangle_quadrature,
)

__all__ = [
    "ErrorNorms",
    "Quadrature",
    "energy_error",
    "h1_seminorm_error",
    "l2_error",
    "rectangle_quadrature",
]
