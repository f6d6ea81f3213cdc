"""mlsgalerkin: meshfree Galerkin mechanics.

MLS/RKPM/Shepard/orthogonal shape functions with exact gradients on a library of kernels,
with a numba cell-list neighbour search. Start with :func:`shape_functions`.
"""

from mlsgalerkin.approximation import (
    ShapeFunctionFallbackError,
    ShapeFunctionFallbackWarning,
    ShapeTable,
    shape_functions,
)
from mlsgalerkin.kernels import KERNELS, Kernel, get_kernel
from mlsgalerkin.neighbors import NeighborTable, find_neighbors

__version__ = "0.1.0"

__all__ = [
    "KERNELS",
    "Kernel",
    "NeighborTable",
    "ShapeFunctionFallbackError",
    "ShapeFunctionFallbackWarning",
    "ShapeTable",
    "__version__",
    "find_neighbors",
    "get_kernel",
    "shape_functions",
]
