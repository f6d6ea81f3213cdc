r"""Broad phase of the contact search: which facets each slave node may touch.

A slave node ``x_s`` is a *candidate* of facet ``j`` when it lies inside the facet's
axis-aligned bounding box grown by ``margin`` on every side,

.. math:: \min_a x_{a,\alpha} - \text{margin} \le x_{s,\alpha} \le \max_a x_{a,\alpha} + \text{margin}
          \quad\text{for every axis } \alpha,

which holds for every slave within distance ``margin`` of the facet (the narrow phase,
:mod:`mlsgalerkin.contact.penalty`, computes the exact closest point). The penalty contact
uses ``margin = max(g0, reach − g0)``: the farthest a slave in front of the facet (``g0``,
the contact thickness) or behind it (``reach − g0``) can be and still touch it.

:func:`candidate_pairs` bins the grown boxes into a uniform cell grid (cell edge ``≥ 2
margin``: the median grown-box size, over every ``⌈k/1024⌉``-th facet; at most ``max(8 k,
4096)`` cells for ``k`` facets), then tests each slave against the facets of its cell only: ``O(n + k)`` work for
``n`` slaves. The result is in CSR form, ``indices[indptr[s]:indptr[s + 1]]`` the candidate
facets of slave ``s`` in increasing order. :func:`candidate_pairs_reference` tests every
slave against every box (numpy).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

__all__ = ["candidate_pairs", "candidate_pairs_reference", "grown_boxes"]

#: Upper bound on the cell count relative to the facet count (and an absolute floor).
CELLS_PER_FACET = 8
MIN_CELL_CAP = 4096
#: The cell edge is the median box size of at most about this many facets (every k-th).
MEDIAN_SAMPLE = 1024


@numba.njit(cache=True)
def _boxes(nodes, facets, margin, lo, hi):
    for j in range(facets.shape[0]):
        for a in range(nodes.shape[1]):
            v = nodes[facets[j, 0], a]
            lo[j, a] = v
            hi[j, a] = v
            for c in range(1, facets.shape[1]):
                v = nodes[facets[j, c], a]
                lo[j, a] = min(lo[j, a], v)
                hi[j, a] = max(hi[j, a], v)
            lo[j, a] -= margin
            hi[j, a] += margin


@numba.njit(cache=True)
def _corners(lo, hi):
    """Lower corner of all boxes ``lo`` and upper corner of all ``hi`` (a numpy ``min(axis=0)``
    over an ``(k, d)`` array is strided and several times slower)."""
    first = lo[0].copy()
    last = hi[0].copy()
    for j in range(1, lo.shape[0]):
        for a in range(lo.shape[1]):
            first[a] = min(first[a], lo[j, a])
            last[a] = max(last[a], hi[j, a])
    return first, last


def grown_boxes(nodes: NDArray[np.float64], facets: NDArray[np.int64], margin: float
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Lower and upper corners ``(k, d)`` of each facet's bounding box grown by ``margin`` (m)."""
    x = np.ascontiguousarray(nodes, dtype=np.float64)
    f = np.ascontiguousarray(facets, dtype=np.int64)
    lo, hi = np.empty((f.shape[0], x.shape[1])), np.empty((f.shape[0], x.shape[1]))
    _boxes(x, f, float(margin), lo, hi)
    return lo, hi


@numba.njit(cache=True)
def _cell_range(lo, hi, j, origin, cell, dims, first, last):
    """First and last cell index along each axis covered by box ``j`` (clamped to the grid)."""
    for a in range(lo.shape[1]):
        first[a] = min(max(int(math.floor((lo[j, a] - origin[a]) / cell)), 0), dims[a] - 1)
        last[a] = min(max(int(math.floor((hi[j, a] - origin[a]) / cell)), 0), dims[a] - 1)
    if lo.shape[1] == 2:
        first[2] = 0
        last[2] = 0


@numba.njit(cache=True)
def _bin(lo, hi, origin, cell, dims):
    """Cell → facets in CSR form (each facet in every cell its box overlaps, in facet order)."""
    k, dim = lo.shape
    d2 = dims[2] if dim == 3 else 1
    ncell = dims[0] * dims[1] * d2
    start = np.zeros(ncell + 1, dtype=np.int64)
    first = np.zeros(3, dtype=np.int64)
    last = np.zeros(3, dtype=np.int64)
    for j in range(k):
        _cell_range(lo, hi, j, origin, cell, dims, first, last)
        for i0 in range(first[0], last[0] + 1):
            for i1 in range(first[1], last[1] + 1):
                for i2 in range(first[2], last[2] + 1):
                    start[(i0 * dims[1] + i1) * d2 + i2 + 1] += 1
    for c in range(ncell):
        start[c + 1] += start[c]
    cells = np.empty(start[ncell], dtype=np.int64)
    fill = start[:ncell].copy()
    for j in range(k):
        _cell_range(lo, hi, j, origin, cell, dims, first, last)
        for i0 in range(first[0], last[0] + 1):
            for i1 in range(first[1], last[1] + 1):
                for i2 in range(first[2], last[2] + 1):
                    c = (i0 * dims[1] + i1) * d2 + i2
                    cells[fill[c]] = j
                    fill[c] += 1
    return start, cells


@numba.njit(cache=True, inline="always")
def _cell_of(x, s, origin, cell, dims):
    dim = x.shape[1]
    c = 0
    for a in range(dim):
        i = int(math.floor((x[s, a] - origin[a]) / cell))
        if i < 0 or i >= dims[a]:
            return -1
        c = c * dims[a] + i
    return c


@numba.njit(cache=True, inline="always")
def _inside(x, s, lo, hi, j):
    for a in range(x.shape[1]):
        if x[s, a] < lo[j, a] or x[s, a] > hi[j, a]:
            return False
    return True


@numba.njit(parallel=True, cache=True)
def _count(x, lo, hi, origin, cell, dims, cell_start, cell_facets, counts):
    for s in prange(x.shape[0]):
        c = _cell_of(x, s, origin, cell, dims)
        n = 0
        if c >= 0:
            for q in range(cell_start[c], cell_start[c + 1]):
                if _inside(x, s, lo, hi, cell_facets[q]):
                    n += 1
        counts[s] = n


@numba.njit(parallel=True, cache=True)
def _fill(x, lo, hi, origin, cell, dims, cell_start, cell_facets, indptr, indices):
    for s in prange(x.shape[0]):
        c = _cell_of(x, s, origin, cell, dims)
        if c < 0:
            continue
        w = indptr[s]
        for q in range(cell_start[c], cell_start[c + 1]):
            j = cell_facets[q]
            if _inside(x, s, lo, hi, j):
                indices[w] = j
                w += 1


def candidate_pairs(points: NDArray[np.float64], nodes: NDArray[np.float64], facets: NDArray[np.int64],
                    margin: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Candidate facets of each slave: ``(indptr (n + 1,), indices)`` in CSR form (numba).

    ``points (n, d)`` slave positions, ``nodes (m, d)`` and ``facets (k, d)`` the master
    surface, ``margin`` (m, >= 0) the growth of each facet's bounding box (module docstring).
    """
    x = np.ascontiguousarray(points, dtype=np.float64)
    n, dim = x.shape
    f = np.ascontiguousarray(facets, dtype=np.int64)
    lo, hi = grown_boxes(nodes, f, float(margin))
    k = f.shape[0]
    indptr = np.zeros(n + 1, dtype=np.int64)
    if n == 0 or k == 0:
        return indptr, np.zeros(0, dtype=np.int64)
    origin, top = _corners(lo, hi)
    extent = top - origin
    every = max(1, k // MEDIAN_SAMPLE)  # the median box size of a sample of the facets
    size = float(np.median((hi[::every] - lo[::every]).max(axis=1)))  # grown boxes: >= 2 margin
    cell = max(size, 1e-12 * max(float(extent.max()), 1.0))
    cap = max(CELLS_PER_FACET * k, MIN_CELL_CAP)
    dims = np.maximum(np.floor(extent / cell).astype(np.int64) + 1, 1)
    while float(np.prod(dims.astype(float))) > cap:  # too fine for the domain: coarsen
        cell *= (float(np.prod(dims.astype(float))) / cap) ** (1.0 / dim) * 1.01
        dims = np.maximum(np.floor(extent / cell).astype(np.int64) + 1, 1)
    cell_start, cell_facets = _bin(lo, hi, origin, cell, dims)
    counts = np.empty(n, dtype=np.int64)
    _count(x, lo, hi, origin, cell, dims, cell_start, cell_facets, counts)
    np.cumsum(counts, out=indptr[1:])
    indices = np.empty(int(indptr[-1]), dtype=np.int64)
    _fill(x, lo, hi, origin, cell, dims, cell_start, cell_facets, indptr, indices)
    return indptr, indices


def candidate_pairs_reference(points: NDArray[np.float64], nodes: NDArray[np.float64], facets: NDArray[np.int64],
                              margin: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Numpy version of :func:`candidate_pairs`: every slave against every grown box (the boxes
    from numpy too, not from :func:`grown_boxes`)."""
    x = np.asarray(points, dtype=float)
    corners = np.asarray(nodes, dtype=float)[np.asarray(facets)]
    lo, hi = corners.min(axis=1) - float(margin), corners.max(axis=1) + float(margin)
    inside = np.all((x[:, None, :] >= lo[None]) & (x[:, None, :] <= hi[None]), axis=2)  # (n, k)
    indptr = np.concatenate([[0], np.cumsum(inside.sum(axis=1))]).astype(np.int64)
    return indptr, np.nonzero(inside)[1].astype(np.int64)
