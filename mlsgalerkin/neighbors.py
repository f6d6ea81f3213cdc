"""Fixed-radius neighbour search: evaluation points against nodes, as a CSR table.

A pair ``(i, j)`` belongs to the table when ``|x_i - y_j| < r``, where ``r`` is either

* the radius of the *evaluation point* (``radius=``: a scalar or one per point, "gather"), or
* the radius of the *node* (``node_radius=``: one per node, "scatter"), the natural choice for
  meshfree shape functions whose nodal support is ``kappa * h_j``.

The search is a cell-linked list: nodes are binned on a uniform grid and counting-sorted by cell,
evaluation points are visited in cell order (so neighbouring queries touch the same memory) and
each query tests only the cells overlapping its search ball, in a single distance pass per query.
Work is split into chunks of queries processed in parallel (numba ``prange``); each chunk writes
into a region sized by an exact upper bound (the occupancy of the cells it will visit), so the
pass never overflows. :func:`brute_force_neighbors` is the O(n m) numpy reference.

Periodic domains (``period=``, ``lower=``; :mod:`mlsgalerkin.periodic`): the nodes within the
search reach of a periodic axis' ends are copied once more, shifted by ``±L`` across the seam
(axis by axis, so the corners of a doubly periodic box get their diagonal images), the same cell
list searches the nodes and their images, and each image's hit is reported as its source node.
The pairs are those of the minimum-image distance; each pair appears once because a period must
be at least twice the search radius.

Example
-------
>>> import numpy as np
>>> from mlsgalerkin.neighbors import find_neighbors
>>> nodes = np.random.default_rng(0).random((100, 2))
>>> table = find_neighbors(nodes, nodes, radius=0.2)
>>> table.indptr.shape, table.n_points
((101,), 100)
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numba import prange
from numpy.typing import ArrayLike, NDArray

__all__ = ["NeighborTable", "find_neighbors", "brute_force_neighbors", "as_coordinates"]

_CHUNK = 256
_MAX_CELLS_PER_NODE = 4


@dataclass(frozen=True)
class NeighborTable:
    """Neighbours of ``n_points`` evaluation points among ``n_nodes`` nodes, in CSR form.

    Attributes
    ----------
    indptr : (n_points + 1,) int64
        Row ``i`` holds ``indices[indptr[i]:indptr[i + 1]]``.
    indices : (n_pairs,) int32
        Node indices. Within a row the order is deterministic but not sorted.
    n_nodes : int
    """

    indptr: NDArray[np.int64]
    indices: NDArray[np.int32]
    n_nodes: int

    @property
    def n_points(self) -> int:
        return self.indptr.shape[0] - 1

    @property
    def n_pairs(self) -> int:
        return int(self.indptr[-1])

    @property
    def counts(self) -> NDArray[np.int64]:
        """Number of neighbours of each evaluation point, ``(n_points,)``."""
        return np.diff(self.indptr)

    def rows(self) -> NDArray[np.int64]:
        """Evaluation-point index of each pair, ``(n_pairs,)`` (the CSR row, expanded)."""
        return np.repeat(np.arange(self.n_points, dtype=np.int64), self.counts)

    def sorted(self) -> "NeighborTable":
        """A copy with every row sorted by node index."""
        rows = self.rows()
        order = np.lexsort((self.indices, rows))
        return NeighborTable(self.indptr.copy(), self.indices[order], self.n_nodes)

    def to_csr(self):
        """A ``scipy.sparse.csr_array`` of ones with shape ``(n_points, n_nodes)``."""
        from scipy.sparse import csr_array

        data = np.ones(self.n_pairs)
        return csr_array((data, self.indices, self.indptr), shape=(self.n_points, self.n_nodes))


def as_coordinates(name: str, x: ArrayLike, dim: int | None = None) -> NDArray[np.float64]:
    """Validate coordinates and return them as a C-contiguous ``(n, dim)`` float64 array.

    A 1-D array of length ``n`` is read as ``n`` points on a line. Raises ``ValueError`` for
    empty input, more than three columns, a dimension that differs from ``dim``, or any
    non-finite coordinate (naming the first offending row).
    """
    a = np.asarray(x, dtype=np.float64)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise ValueError(f"{name} must have shape (n, dim), got an array of shape {a.shape}")
    if a.shape[0] == 0:
        raise ValueError(f"{name} is empty: give at least one point")
    if not 1 <= a.shape[1] <= 3:
        raise ValueError(f"{name} must have 1, 2 or 3 columns (the dimension), got {a.shape[1]}")
    if dim is not None and a.shape[1] != dim:
        raise ValueError(
            f"{name} has dimension {a.shape[1]} but the nodes have dimension {dim}; "
            "give both in the same space"
        )
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"{name} has {int(bad.sum())} row(s) with NaN or inf coordinates, first at row {k}: "
            f"{a[k].tolist()}; remove or fix them"
        )
    return np.ascontiguousarray(a)


def _radius_array(name: str, r: ArrayLike, n: int, what: str) -> NDArray[np.float64]:
    a = np.asarray(r, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(n, float(a))
    elif a.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have one value per {what} ({n}), got shape {a.shape}")
    bad = ~(np.isfinite(a) & (a > 0))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{name} must be positive and finite; entry {k} is {float(a[k])}")
    return np.ascontiguousarray(a)


def _resolve_radii(points, nodes, radius, node_radius):
    if (radius is None) == (node_radius is None):
        raise ValueError(
            "give exactly one of radius= (per evaluation point) or node_radius= (per node)"
        )
    if radius is not None:
        return _radius_array("radius", radius, points.shape[0], "evaluation point"), False
    return _radius_array("node_radius", node_radius, nodes.shape[0], "node"), True


def find_neighbors(
    points: ArrayLike,
    nodes: ArrayLike,
    radius: ArrayLike | None = None,
    *,
    node_radius: ArrayLike | None = None,
    period: ArrayLike | None = None,
    lower: ArrayLike | None = None,
) -> NeighborTable:
    """All nodes within a radius of each evaluation point, by a numba cell-linked list.

    Parameters
    ----------
    points : (n_points, dim) float array
        Evaluation points (may be the nodes themselves, or anywhere else).
    nodes : (n_nodes, dim) float array
    radius : float or (n_points,) float array, optional
        Search radius of each evaluation point: pair if ``|x_i - y_j| < radius_i``.
    node_radius : float or (n_nodes,) float array, optional
        Support radius of each node: pair if ``|x_i - y_j| < node_radius_j``.

    period : one value per axis (m), optional
        Periods of a periodic domain (``0``: the axis is not periodic): pairs are found across
        the seam, by the minimum-image distance. Every period must be at least twice the largest
        radius, and every point and node must lie in ``[lower, lower + period)`` on its periodic axes.
    lower : one value per axis (m), optional
        Lower ends of the periodic axes (default ``0``).

    Exactly one of ``radius`` and ``node_radius`` must be given.

    Returns
    -------
    NeighborTable
    """
    nodes_a = as_coordinates("nodes", nodes)
    points_a = nodes_a if points is nodes else as_coordinates("points", points, nodes_a.shape[1])
    r, scatter = _resolve_radii(points_a, nodes_a, radius, node_radius)
    if period is not None and np.any(np.asarray(period, dtype=float) > 0):
        indptr, indices = _periodic_search(points_a, nodes_a, r, scatter, period, lower)
    else:
        indptr, indices = _cell_list_search(points_a, nodes_a, r, scatter, points is nodes)
    return NeighborTable(indptr, indices, nodes_a.shape[0])


def _periodic_box(dim: int, period: ArrayLike, lower: ArrayLike | None):
    """``(period (dim,), lower (dim,))`` from one value per axis (fewer: the rest 0)."""
    p = np.zeros(dim)
    given = np.asarray(period, dtype=float).ravel()[:dim]
    p[: given.size] = given
    lo = np.zeros(dim)
    if lower is not None:
        given = np.asarray(lower, dtype=float).ravel()[:dim]
        lo[: given.size] = given
    if not (np.isfinite(p).all() and (p >= 0).all() and np.isfinite(lo).all()):
        raise ValueError(f"period must be non-negative and finite and lower finite, got {period!r}, {lower!r}")
    return p, lo


def _periodic_search(points, nodes, r, scatter, period, lower):
    """The cell-list search over the nodes and their images across each periodic seam."""
    dim = nodes.shape[1]
    p, lo = _periodic_box(dim, period, lower)
    reach = float(r.max())
    for a in np.flatnonzero(p > 0):
        if p[a] < 2.0 * reach:
            raise ValueError(
                f"the period along axis {'xyz'[a]} ({p[a]:g} m) is shorter than twice the search radius "
                f"({reach:g} m): a particle would meet another and its image; lengthen the periodic box"
            )
        for name, x in (("points", points), ("nodes", nodes)):
            out = (x[:, a] < lo[a]) | (x[:, a] >= lo[a] + p[a])
            if out.any():
                k = int(np.flatnonzero(out)[0])
                raise ValueError(
                    f"{name} {k} at {x[k].tolist()} lies outside the periodic interval [{lo[a]:g}, "
                    f"{lo[a] + p[a]:g}) of axis {'xyz'[a]}; wrap the positions into the box first"
                )
    ext, source = nodes, np.arange(nodes.shape[0])
    rn = r if scatter else None
    for a in np.flatnonzero(p > 0):
        near_lo = np.flatnonzero(ext[:, a] < lo[a] + reach)           # their images lie past the upper end
        near_hi = np.flatnonzero(ext[:, a] >= lo[a] + p[a] - reach)   # and these before the lower end
        up, down = ext[near_lo].copy(), ext[near_hi].copy()
        up[:, a] += p[a]
        down[:, a] -= p[a]
        ext = np.concatenate([ext, up, down])
        source = np.concatenate([source, source[near_lo], source[near_hi]])
        if scatter:
            rn = np.concatenate([rn, rn[near_lo], rn[near_hi]])
    indptr, indices = _cell_list_search(points, np.ascontiguousarray(ext), rn if scatter else r, scatter, False)
    return indptr, source[indices].astype(np.int32)


def brute_force_neighbors(
    points: ArrayLike,
    nodes: ArrayLike,
    radius: ArrayLike | None = None,
    *,
    node_radius: ArrayLike | None = None,
    period: ArrayLike | None = None,
) -> NeighborTable:
    """Reference all-pairs search (numpy, O(n_points * n_nodes)); rows sorted by node index;
    ``period`` (one per axis, m): minimum-image distances along the periodic axes."""
    nodes_a = as_coordinates("nodes", nodes)
    points_a = as_coordinates("points", points, nodes_a.shape[1])
    r, scatter = _resolve_radii(points_a, nodes_a, radius, node_radius)
    per = _periodic_box(nodes_a.shape[1], period, None)[0] if period is not None else np.zeros(nodes_a.shape[1])
    rows, cols = [], []
    block = max(1, 2_000_000 // nodes_a.shape[0])
    for s in range(0, points_a.shape[0], block):
        p = points_a[s : s + block]
        d2 = np.zeros((p.shape[0], nodes_a.shape[0]))
        with np.errstate(over="ignore"):  # far-apart points: d2 = inf is the right answer
            for k in range(nodes_a.shape[1]):
                diff = p[:, k, None] - nodes_a[None, :, k]
                if per[k] > 0:
                    diff -= per[k] * np.floor(diff / per[k] + 0.5)
                d2 += diff**2
        r2 = (r[None, :] ** 2) if scatter else (r[s : s + block, None] ** 2)
        i, j = np.nonzero(d2 < r2)
        rows.append(i + s)
        cols.append(j)
    rows_a = np.concatenate(rows)
    cols_a = np.concatenate(cols).astype(np.int32)
    indptr = np.zeros(points_a.shape[0] + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows_a, minlength=points_a.shape[0]), out=indptr[1:])
    return NeighborTable(indptr, cols_a, nodes_a.shape[0])


# --------------------------------------------------------------------------------------
# cell list
# --------------------------------------------------------------------------------------


def _grid(nodes: np.ndarray, cell_size: float):
    """Grid origin, cell size and cells per axis (padded to 3 axes), capped in total size."""
    lo, hi = _bounds(nodes)
    extent = hi - lo
    dim = nodes.shape[1]
    max_cells = _MAX_CELLS_PER_NODE * nodes.shape[0] + 64
    cs = float(cell_size)
    while True:
        # cell counts in float: extent / cs may exceed int64 (or be inf) for a tiny radius
        with np.errstate(over="ignore"):
            n = np.floor(extent / cs) + 1.0
        if np.prod(n) <= max_cells:
            break
        cs *= 1.25
    ncell = np.ones(3, dtype=np.int64)
    ncell[:dim] = n.astype(np.int64)
    origin = np.zeros(3)
    origin[:dim] = lo
    return origin, cs, ncell


@numba.njit(cache=True)
def _bounds(x):
    lo = x[0].copy()
    hi = x[0].copy()
    for i in range(1, x.shape[0]):
        for k in range(x.shape[1]):
            lo[k] = min(lo[k], x[i, k])
            hi[k] = max(hi[k], x[i, k])
    return lo, hi


@numba.njit(cache=True)
def _cell_ids(x, origin, cs, ncell):
    n, dim = x.shape
    out = np.empty(n, dtype=np.int64)
    for i in range(n):
        cid = 0
        stride = 1
        for k in range(dim):
            # clamp in float first: a point far outside the grid would overflow int64
            c = int(min(max(np.floor((x[i, k] - origin[k]) / cs), 0.0), float(ncell[k] - 1)))
            cid += c * stride
            stride *= ncell[k]
        out[i] = cid
    return out


@numba.njit(cache=True)
def _counting_sort(cell, n_cells):
    """Permutation that sorts ``cell`` (stable) and the start of each cell, ``(n_cells + 1,)``."""
    start = np.zeros(n_cells + 1, dtype=np.int64)
    for c in cell:
        start[c + 1] += 1
    for c in range(n_cells):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(cell.shape[0], dtype=np.int64)
    for i in range(cell.shape[0]):
        c = cell[i]
        order[fill[c]] = i
        fill[c] += 1
    return order, start


@numba.njit(cache=True, inline="always")
def _cell_range(x, i, reach, origin, cs, ncell, dim, lo, hi):
    """Cells overlapping [x - reach, x + reach] per axis; False if the box misses the grid."""
    for k in range(3):
        lo[k] = 0
        hi[k] = 0
    for k in range(dim):
        # clip in float before converting: a huge reach (or far point) would overflow int64
        a = np.floor((x[i, k] - reach - origin[k]) / cs)
        b = np.floor((x[i, k] + reach - origin[k]) / cs)
        if b < 0 or a > ncell[k] - 1:
            return False
        lo[k] = int(max(a, 0.0))
        hi[k] = int(min(b, float(ncell[k] - 1)))
    return True


@numba.njit(parallel=True, cache=True)
def _search_kernel(spoints, q_order, snodes, snode_ids, cell_start, origin, cs, ncell, rq, rn, scatter, reach_max):
    """``spoints``/``rq`` are in query-visit order (``q_order``), ``snodes``/``rn`` in cell order."""
    n_q, dim = spoints.shape
    n_chunks = (n_q + _CHUNK - 1) // _CHUNK
    nx, ny = ncell[0], ncell[1]

    # pass 1: an upper bound of each chunk's output (occupancy of the visited cells)
    cap = np.zeros(n_chunks + 1, dtype=np.int64)
    for c in prange(n_chunks):
        lo = np.empty(3, dtype=np.int64)
        hi = np.empty(3, dtype=np.int64)
        s = 0
        for t in range(c * _CHUNK, min((c + 1) * _CHUNK, n_q)):
            reach = reach_max if scatter else rq[t]
            if not _cell_range(spoints, t, reach, origin, cs, ncell, dim, lo, hi):
                continue
            for cz in range(lo[2], hi[2] + 1):
                for cy in range(lo[1], hi[1] + 1):
                    base = (cz * ny + cy) * nx
                    s += cell_start[base + hi[0] + 1] - cell_start[base + lo[0]]
        cap[c + 1] = s
    for c in range(n_chunks):
        cap[c + 1] += cap[c]

    # pass 2: distances, written compactly inside each chunk's region
    tmp = np.empty(cap[n_chunks], dtype=np.int32)
    start = np.empty(n_q, dtype=np.int64)
    count = np.empty(n_q, dtype=np.int64)
    for c in prange(n_chunks):
        lo = np.empty(3, dtype=np.int64)
        hi = np.empty(3, dtype=np.int64)
        pos = cap[c]
        for t in range(c * _CHUNK, min((c + 1) * _CHUNK, n_q)):
            i = q_order[t]
            start[i] = pos
            reach = reach_max if scatter else rq[t]
            if _cell_range(spoints, t, reach, origin, cs, ncell, dim, lo, hi):
                r2 = rq[t] * rq[t] if not scatter else 0.0
                for cz in range(lo[2], hi[2] + 1):
                    for cy in range(lo[1], hi[1] + 1):
                        base = (cz * ny + cy) * nx
                        k0 = cell_start[base + lo[0]]
                        k1 = cell_start[base + hi[0] + 1]
                        # branch-free append: write always, advance only on a hit. pos never
                        # passes the number of candidates seen, so it stays inside the region.
                        if scatter:
                            for k in range(k0, k1):
                                d2 = 0.0
                                for a in range(dim):
                                    dx = spoints[t, a] - snodes[k, a]
                                    d2 += dx * dx
                                tmp[pos] = snode_ids[k]
                                pos += d2 < rn[k] * rn[k]
                        else:
                            for k in range(k0, k1):
                                d2 = 0.0
                                for a in range(dim):
                                    dx = spoints[t, a] - snodes[k, a]
                                    d2 += dx * dx
                                tmp[pos] = snode_ids[k]
                                pos += d2 < r2
            count[i] = pos - start[i]

    indptr = np.zeros(n_q + 1, dtype=np.int64)
    for i in range(n_q):
        indptr[i + 1] = indptr[i] + count[i]
    indices = np.empty(indptr[n_q], dtype=np.int32)
    for i in prange(n_q):
        s = start[i]
        o = indptr[i]
        for k in range(count[i]):
            indices[o + k] = tmp[s + k]
    return indptr, indices


def _cell_list_search(points, nodes, r, scatter, same):
    # half-radius cells: in 2D a query scans ~36 candidates for ~21 neighbours (52 with r-cells)
    cell_size = 0.5 * (r.max() if scatter else float(np.median(r)))
    origin, cs, ncell = _grid(nodes, cell_size)
    n_cells = int(np.prod(ncell))
    node_cell = _cell_ids(nodes, origin, cs, ncell)
    order, cell_start = _counting_sort(node_cell, n_cells)
    snodes = np.ascontiguousarray(nodes[order])
    if same:
        q_order = order
    else:
        q_order, _ = _counting_sort(_cell_ids(points, origin, cs, ncell), n_cells)
    spoints = snodes if same else np.ascontiguousarray(points[q_order])
    rq = np.ones(1) if scatter else np.ascontiguousarray(r[q_order])
    rn = np.ascontiguousarray(r[order]) if scatter else np.ones(1)
    return _search_kernel(
        spoints, q_order, snodes, order.astype(np.int32), cell_start, origin, cs, ncell,
        rq, rn, scatter, float(r.max()),
    )
