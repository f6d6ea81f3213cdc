"""ShapeTable: shape-function values and gradients per (point, node) pair, in CSR layout."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["ShapeTable"]


@dataclass(frozen=True, eq=False)
class ShapeTable:
    r"""Shape functions :math:`N_j(\mathbf x_i)` and :math:`\nabla N_j(\mathbf x_i)` of nodes at points.

    Pair ``p`` (``indptr[i] <= p < indptr[i + 1]``) couples evaluation point ``i`` with node
    ``indices[p]``; ``values[p]`` and ``gradients[p]`` hold its value and gradient. This is the
    per-pair table the Galerkin assembler consumes.

    Attributes
    ----------
    points : (n_points, dim) float array
    indptr : (n_points + 1,) int64 array
    indices : (n_pairs,) int32 array
    values : (n_pairs,) float array
    gradients : (n_pairs, dim) float array, units 1/length
    n_nodes : int
    requested_order : int
        Polynomial order asked for (0 constant, 1 linear, 2 quadratic).
    order : (n_points,) int8 array
        Order actually used at each point (lower than requested where it fell back).
    condition : (n_points,) float array
        1-norm condition number of the scaled moment matrix at the order used (1 for Shepard).
    method, kernel : str
        How the table was built (for reports).
    kernel_sum : (n_points,) float array or None
        The Shepard sum :math:`c(\mathbf x_i) = \sum_j W(\mathbf x_i - \mathbf x_j, h_j) V_j` of each
        point (dimensionless; about 1 inside a body, about ½ on a flat free surface), when the
        table was built with node volumes for it (``kernel_sum_volumes``); else None.
    kernel_sum_gradient : (n_points, dim) float array or None
        Its gradient :math:`\nabla c(\mathbf x_i)` (1/length; points into the body at a free
        surface), or None.
    """

    points: NDArray[np.float64]
    indptr: NDArray[np.int64]
    indices: NDArray[np.int32]
    values: NDArray[np.float64]
    gradients: NDArray[np.float64]
    n_nodes: int
    requested_order: int
    order: NDArray[np.int8]
    condition: NDArray[np.float64]
    method: str = "mls"
    kernel: str = "cubic_spline"
    meta: dict = field(default_factory=dict, repr=False)
    kernel_sum: NDArray[np.float64] | None = field(default=None, repr=False)
    kernel_sum_gradient: NDArray[np.float64] | None = field(default=None, repr=False)

    # ---- sizes and diagnostics -------------------------------------------------------
    @property
    def n_points(self) -> int:
        return self.points.shape[0]

    @property
    def dim(self) -> int:
        return self.points.shape[1]

    @property
    def n_pairs(self) -> int:
        return self.values.shape[0]

    @property
    def n_neighbors(self) -> NDArray[np.int64]:
        """Neighbour count of each point, ``(n_points,)``."""
        return np.diff(self.indptr)

    @property
    def fallback(self) -> NDArray[np.bool_]:
        """True where a point used a lower order than requested, ``(n_points,)``."""
        return self.order < self.requested_order

    @property
    def n_fallback(self) -> int:
        """Number of points that fell back to a lower order."""
        return int(np.count_nonzero(self.fallback))

    def rows(self) -> NDArray[np.int64]:
        """Evaluation-point index of every pair, ``(n_pairs,)``."""
        return np.repeat(np.arange(self.n_points, dtype=np.int64), self.n_neighbors)

    def diagnostics(self) -> dict:
        """Summary: neighbour counts, condition numbers, fallbacks per order."""
        nb = self.n_neighbors
        return {
            "n_points": self.n_points,
            "n_nodes": self.n_nodes,
            "method": self.method,
            "kernel": self.kernel,
            "requested_order": self.requested_order,
            "neighbors_min": int(nb.min()),
            "neighbors_mean": float(nb.mean()),
            "neighbors_max": int(nb.max()),
            "condition_max": float(self.condition.max()),
            "n_fallback": self.n_fallback,
            "points_per_order": {int(o): int(np.count_nonzero(self.order == o)) for o in np.unique(self.order)},
        }

    # ---- sparse views and evaluation -------------------------------------------------
    @cached_property
    def _value_matrix(self):
        from scipy.sparse import csr_array

        return csr_array((self.values, self.indices, self.indptr), shape=(self.n_points, self.n_nodes))

    @cached_property
    def _gradient_matrices(self):
        from scipy.sparse import csr_array

        shape = (self.n_points, self.n_nodes)
        return tuple(
            csr_array((np.ascontiguousarray(self.gradients[:, k]), self.indices, self.indptr), shape=shape)
            for k in range(self.dim)
        )

    def value_matrix(self):
        """``N`` as a ``scipy.sparse.csr_array`` of shape ``(n_points, n_nodes)``."""
        return self._value_matrix

    def gradient_matrices(self) -> tuple:
        """``(∂N/∂x_1, ..., ∂N/∂x_dim)`` as sparse ``(n_points, n_nodes)`` arrays."""
        return self._gradient_matrices

    def _check_nodal(self, u: ArrayLike) -> NDArray[np.float64]:
        u = np.asarray(u, dtype=float)
        if u.ndim not in (1, 2) or u.shape[0] != self.n_nodes:
            raise ValueError(
                f"nodal values must have shape ({self.n_nodes},) or ({self.n_nodes}, k), "
                f"got {u.shape}"
            )
        return u

    def interpolate(self, u: ArrayLike) -> NDArray[np.float64]:
        r"""``u^h(x_i) = Σ_j N_j(x_i) u_j``: ``(n_nodes,)`` -> ``(n_points,)``, ``(n_nodes, k)`` -> ``(n_points, k)``."""
        return self._value_matrix @ self._check_nodal(u)

    def gradient(self, u: ArrayLike) -> NDArray[np.float64]:
        r"""``∇u^h(x_i) = Σ_j u_j ∇N_j(x_i)``: -> ``(n_points, dim)`` or ``(n_points, k, dim)``."""
        u = self._check_nodal(u)
        return np.stack([g @ u for g in self._gradient_matrices], axis=-1)
