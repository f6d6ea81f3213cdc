"""ShapeTable: shape-function values and gradients per (point, node) pair, in CSR layout."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numba
import numpy as np
from numba import prange
from numpy.typing import ArrayLike, NDArray

__all__ = ["NodeColumns", "ShapeTable"]


@dataclass(frozen=True, eq=False)
class NodeColumns:
    """The pairs of a :class:`ShapeTable` grouped by node (the transposed CSR layout).

    Node ``i``'s pairs are ``pairs[indptr[i]:indptr[i + 1]]`` (indices into the table's pair
    arrays), in ascending evaluation point; ``rows`` holds each one's point. A sum over the
    points a node couples to, taken in this order, is the same number whatever the thread count,
    and equals the serial scatter ``out[indices[p]] += ...`` over the table's rows.

    Attributes
    ----------
    indptr : (n_nodes + 1,) int64 array
    pairs : (n_pairs,) int32 array (int64 past 2³¹ − 1 pairs)
    rows : (n_pairs,) int32 array (likewise)
    """

    indptr: NDArray[np.int64]
    pairs: NDArray[np.integer]
    rows: NDArray[np.integer]
    source: tuple = field(default=(), repr=False)   #: the (indptr, indices) it was built from

    @classmethod
    def of(cls, indptr: NDArray[np.int64], indices: NDArray[np.int32], n_nodes: int) -> NodeColumns:
        """The columns of the CSR structure ``(indptr, indices)`` over ``n_nodes`` nodes."""
        wide = indices.shape[0] >= np.iinfo(np.int32).max
        col_ptr, pairs, rows = _group_pairs_by_node(indptr, indices, n_nodes, max(1, numba.get_num_threads()),
                                                    np.int64 if wide else np.int32)
        return cls(col_ptr, pairs, rows, (indptr, indices))

    def built_from(self, indptr: NDArray[np.int64], indices: NDArray[np.int32]) -> bool:
        """Whether these columns were built from these very arrays (not equal copies)."""
        return len(self.source) == 2 and self.source[0] is indptr and self.source[1] is indices


@numba.njit(parallel=True, cache=True)
def _group_pairs_by_node(indptr, indices, n_nodes, n_blocks, index_type):
    """Stable counting sort of the pairs by node: ``(col_ptr, pairs, rows)`` of :class:`NodeColumns`.

    The rows are cut into ``n_blocks`` ranges counted and placed in parallel; every pair's place
    (by node, then by row) is fixed by integer counts, so the result is the same for any
    ``n_blocks``."""
    n_rows = indptr.shape[0] - 1
    n_pairs = indices.shape[0]
    counts = np.zeros((n_blocks, n_nodes), dtype=np.int64)
    for b in prange(n_blocks):
        for p in range(indptr[(n_rows * b) // n_blocks], indptr[(n_rows * (b + 1)) // n_blocks]):
            counts[b, indices[p]] += 1
    col_ptr = np.empty(n_nodes + 1, dtype=np.int64)
    running = 0
    for i in range(n_nodes):
        col_ptr[i] = running
        for b in range(n_blocks):
            c = counts[b, i]
            counts[b, i] = running
            running += c
    col_ptr[n_nodes] = running
    pairs = np.empty(n_pairs, dtype=index_type)
    rows = np.empty(n_pairs, dtype=index_type)
    for b in prange(n_blocks):
        for k in range((n_rows * b) // n_blocks, (n_rows * (b + 1)) // n_blocks):
            for p in range(indptr[k], indptr[k + 1]):
                i = indices[p]
                t = counts[b, i]
                pairs[t] = p
                rows[t] = k
                counts[b, i] = t + 1
    return col_ptr, pairs, rows


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

    def node_columns(self) -> NodeColumns:
        """The pairs grouped by node (:class:`NodeColumns`), for sums over the points each node
        couples to that do not depend on the thread count. Built in O(n_pairs) on first use and
        kept in ``meta["node_columns"]``; a table built with ``out=`` an earlier one on the same
        neighbour arrays (a step without a neighbour rebuild) inherits them."""
        cols = self.meta.get("node_columns")
        if cols is None or not cols.built_from(self.indptr, self.indices):
            cols = NodeColumns.of(self.indptr, self.indices, self.n_nodes)
            self.meta["node_columns"] = cols
        return cols

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
