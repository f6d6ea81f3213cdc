r"""Pair geometry of particles: the offset between two particles and its squared length, once.

Every particle kernel loops over the pairs ``(i, j)`` of a neighbour table (CSR ``indptr``,
``indices``) and needs the offset :math:`\mathbf x_{ji} = \mathbf x_j - \mathbf x_i` (m) and
:math:`r^2 = |\mathbf x_{ji}|^2` (m²) before anything else. :func:`pair_offset` computes them
inside a numba kernel (``inline="always"``: no call overhead) for positions ``x`` of shape
``(n, d)``, ``d = 1, 2, 3``; the components beyond ``d`` are ``0.0``. The offset ``x_i − x_j`` is
its negation (exact in floating point), and so are the dot products with it.

Rounding: :math:`r^2 = d_0^2 + d_1^2 + d_2^2` summed left to right, the same bits as a loop
``r2 += d*d`` over the dimensions from ``0.0`` (adding ``0.0`` is exact).

:func:`pair_offsets` evaluates it over a whole table (the agreement test's kernel) and
:func:`pair_offsets_reference` is its numpy reference.

>>> x = np.array([[0.0, 0.0], [3.0, 4.0]])
>>> d, r2 = pair_offsets(x, np.array([0, 1, 2]), np.array([1, 0], dtype=np.int32))
>>> d.tolist(), r2.tolist()
([[3.0, 4.0, 0.0], [-3.0, -4.0, 0.0]], [25.0, 25.0])
"""

from __future__ import annotations

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

from mlsgalerkin.periodic import as_period, minimum_image

__all__ = ["image_component", "pair_offset", "pair_offsets", "pair_offsets_reference"]


@numba.njit(cache=True, inline="always")
def image_component(d, period):
    """The minimum image ``d − L ⌊d/L + ½⌋`` of one offset component ``d`` (m) for a period
    ``L > 0`` (m), in ``[−L/2, L/2)``; ``d`` itself (the same bits) for ``L = 0``."""
    if period > 0.0:
        return d - period * np.floor(d / period + 0.5)
    return d


@numba.njit(cache=True, inline="always")
def pair_offset(x, i, j, period):
    """``(d0, d1, d2, r2)``: the offset ``x[j] − x[i]`` (m; components beyond ``x.shape[1]`` are 0)
    and its squared length (m²), for positions ``x`` ``(n, d)``, ``d ≤ 3``; along an axis with
    ``period[a] > 0`` (m) the minimum image ``d_a − L_a ⌊d_a/L_a + ½⌋`` (:mod:`mlsgalerkin.periodic`).
    ``period`` is a tuple of three floats, all zeros for a domain without periodic axes."""
    dim = x.shape[1]
    d0 = x[j, 0] - x[i, 0]
    d1 = x[j, 1] - x[i, 1] if dim > 1 else 0.0
    d2 = x[j, 2] - x[i, 2] if dim > 2 else 0.0
    d0 = image_component(d0, period[0])
    d1 = image_component(d1, period[1])
    d2 = image_component(d2, period[2])
    return d0, d1, d2, d0 * d0 + d1 * d1 + d2 * d2


@numba.njit(parallel=True, cache=True)
def _offsets(x, indptr, indices, period, d, r2):
    for i in prange(indptr.shape[0] - 1):
        for q in range(indptr[i], indptr[i + 1]):
            d0, d1, d2, rr = pair_offset(x, i, indices[q], period)
            d[q, 0] = d0
            d[q, 1] = d1
            d[q, 2] = d2
            r2[q] = rr


def pair_offsets(x: NDArray[np.float64], indptr: NDArray[np.int64], indices: NDArray[np.int32],
                 period: NDArray[np.float64] | None = None,
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Offsets ``x_j − x_i`` ``(nnz, 3)`` (m) and squared distances ``(nnz,)`` (m²) of every pair of
    the CSR table ``indptr`` ``(n + 1,)``, ``indices`` ``(nnz,)``, by :func:`pair_offset`
    (``period (3,)``: the minimum image along the axes with a nonzero period; default none)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    d = np.zeros((indices.shape[0], 3))
    r2 = np.zeros(indices.shape[0])
    period = as_period(period)
    _offsets(x, np.ascontiguousarray(indptr, dtype=np.int64), np.ascontiguousarray(indices), period, d, r2)
    return d, r2


def pair_offsets_reference(x: NDArray[np.float64], indptr: NDArray[np.int64], indices: NDArray[np.int32],
                           period: NDArray[np.float64] | None = None,
                           ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Numpy version of :func:`pair_offsets` (tests)."""
    x = np.asarray(x, dtype=np.float64)
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    d = np.zeros((len(indices), 3))
    d[:, : x.shape[1]] = x[indices] - x[rows]
    if period is not None:
        d = minimum_image(d, as_period(period))
    r2 = np.zeros(len(indices))
    for a in range(3):              # left to right, as the kernel sums
        r2 = r2 + d[:, a] * d[:, a]
    return d, r2
