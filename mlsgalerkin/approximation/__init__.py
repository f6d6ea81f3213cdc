"""Meshfree approximation: MLS, RKPM, Shepard and orthogonal-basis shape functions.

See :func:`shape_functions` (the public entry point) and :class:`ShapeTable`;
:func:`implicit_second_derivatives` gives second derivatives from a quadratic least-squares fit.
"""

from mlsgalerkin.approximation.build import (
    METHODS,
    ShapeFunctionFallbackError,
    ShapeFunctionFallbackWarning,
    evaluate_shape_functions,
    shape_functions,
)
from mlsgalerkin.approximation.implicit_derivatives import implicit_second_derivatives
from mlsgalerkin.approximation.table import ShapeTable

__all__ = [
    "METHODS",
    "ShapeFunctionFallbackError",
    "ShapeFunctionFallbackWarning",
    "ShapeTable",
    "evaluate_shape_functions",
    "implicit_second_derivatives",
    "shape_functions",
]
