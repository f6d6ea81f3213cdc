"""Meshfree approximation: MLS, RKPM, Shepard and orthogonal-basis shape functions.

See :func:`shape_functions` (the public entry point) and :class:`ShapeTable`.
"""

from mlsgalerkin.approximation.build import (
    METHODS,
    ShapeFunctionFallbackError,
    ShapeFunctionFallbackWarning,
    evaluate_shape_functions,
    shape_functions,
)
from mlsgalerkin.approximation.table import ShapeTable

__all__ = [
    "METHODS",
    "ShapeFunctionFallbackError",
    "ShapeFunctionFallbackWarning",
    "ShapeTable",
    "evaluate_shape_functions",
    "shape_functions",
]
