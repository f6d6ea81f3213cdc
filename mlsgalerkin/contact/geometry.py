r"""Closest points on facets, facet normals and signed distances (numba kernels, numpy references).

For a point :math:`\mathbf x` and a facet with nodes :math:`\mathbf x_a`, the closest point
:math:`\mathbf x_c = \sum_a N_a\,\mathbf x_a` is given by its facet coordinates (the linear
shape functions of the facet at :math:`\mathbf x_c`, :math:`N_a \ge 0`, :math:`\sum_a N_a = 1`):

- **segment** ``a, b`` (2D): :math:`\xi = \operatorname{clip}\big((\mathbf x - \mathbf x_a)\cdot
  \mathbf t / |\mathbf t|^2, 0, 1\big)`, :math:`\mathbf t = \mathbf x_b - \mathbf x_a`,
  :math:`N = (1 - \xi, \xi)`;
- **triangle** ``a, b, c`` (3D): barycentric coordinates of the closest point, found by the
  Voronoi-region tests of Ericson (2005), *Real-Time Collision Detection*, §5.1.5.

The *region* of the closest point is :data:`INTERIOR` (the projection falls inside the facet),
:data:`EDGE` (on an edge of a triangle) or :data:`VERTEX` (on a node); a clamped projection
(``EDGE`` or ``VERTEX``) means the point lies beyond the facet's border. The outward unit
normal :math:`\mathbf n` follows :class:`~mlsgalerkin.contact.surface.ContactSurface`
(2D: :math:`(t_y, -t_x)/|\mathbf t|`; 3D: :math:`(\mathbf x_b-\mathbf x_a)\times
(\mathbf x_c-\mathbf x_a)` normalised), and the signed distance is
:math:`d = (\mathbf x - \mathbf x_c)\cdot\mathbf n` (m; negative behind the facet). A contact
gap subtracts the contact thickness, :math:`g = d - g_0` (see
:mod:`mlsgalerkin.contact.penalty`).

The scalar kernels (:func:`closest_on_facet`) are called inside the penalty kernel;
:func:`closest_points` evaluates many point–facet pairs at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

__all__ = [
    "EDGE", "INTERIOR", "VERTEX", "ClosestPoints", "closest_on_facet", "closest_points", "closest_points_reference",
    "facet_normals", "facet_normals_reference",
]

#: Region codes of a closest point on a facet.
INTERIOR, EDGE, VERTEX = 0, 1, 2


@numba.njit(cache=True, inline="always")
def _segment(px, py, ax, ay, bx, by):
    """``(ξ, region)`` of the closest point to ``p`` on the segment ``a b``."""
    ex = bx - ax
    ey = by - ay
    t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
    if t <= 0.0:
        return 0.0, VERTEX
    if t >= 1.0:
        return 1.0, VERTEX
    return t, INTERIOR


@numba.njit(cache=True, inline="always")
def _triangle(p0, p1, p2, a0, a1, a2, b0, b1, b2, c0, c1, c2):
    """Barycentric ``(u, v, w, region)`` of the closest point to ``p`` on the triangle ``a b c``
    (Ericson 2005, §5.1.5)."""
    ab0, ab1, ab2 = b0 - a0, b1 - a1, b2 - a2
    ac0, ac1, ac2 = c0 - a0, c1 - a1, c2 - a2
    ap0, ap1, ap2 = p0 - a0, p1 - a1, p2 - a2
    d1 = ab0 * ap0 + ab1 * ap1 + ab2 * ap2
    d2 = ac0 * ap0 + ac1 * ap1 + ac2 * ap2
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0, VERTEX
    bp0, bp1, bp2 = p0 - b0, p1 - b1, p2 - b2
    d3 = ab0 * bp0 + ab1 * bp1 + ab2 * bp2
    d4 = ac0 * bp0 + ac1 * bp1 + ac2 * bp2
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0, VERTEX
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return 1.0 - v, v, 0.0, EDGE
    cp0, cp1, cp2 = p0 - c0, p1 - c1, p2 - c2
    d5 = ab0 * cp0 + ab1 * cp1 + ab2 * cp2
    d6 = ac0 * cp0 + ac1 * cp1 + ac2 * cp2
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0, VERTEX
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return 1.0 - w, 0.0, w, EDGE
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - w, w, EDGE
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    return 1.0 - v - w, v, w, INTERIOR


@numba.njit(cache=True, inline="always")
def closest_on_facet(x, i, nodes, facets, j):
    """Facet coordinates ``(N_0, N_1, N_2, region)`` of the closest point to ``x[i]`` on facet
    ``j`` (``N_2 = 0`` for a 2D segment). numba-compiled and inlined into its callers (2–2.5×
    faster penalty kernel than a call); ``x (n, d)``, ``nodes (m, d)``, ``facets (k, d)``."""
    if x.shape[1] == 2:
        a = facets[j, 0]
        b = facets[j, 1]
        xi, region = _segment(x[i, 0], x[i, 1], nodes[a, 0], nodes[a, 1], nodes[b, 0], nodes[b, 1])
        return 1.0 - xi, xi, 0.0, region
    a = facets[j, 0]
    b = facets[j, 1]
    c = facets[j, 2]
    return _triangle(x[i, 0], x[i, 1], x[i, 2], nodes[a, 0], nodes[a, 1], nodes[a, 2],
                     nodes[b, 0], nodes[b, 1], nodes[b, 2], nodes[c, 0], nodes[c, 1], nodes[c, 2])


@numba.njit(cache=True)
def _normals(nodes, facets, out):
    dim = nodes.shape[1]
    for j in range(facets.shape[0]):
        a = facets[j, 0]
        b = facets[j, 1]
        if dim == 2:
            tx = nodes[b, 0] - nodes[a, 0]
            ty = nodes[b, 1] - nodes[a, 1]
            length = np.sqrt(tx * tx + ty * ty)
            out[j, 0] = ty / length
            out[j, 1] = -tx / length
        else:
            c = facets[j, 2]
            u0, u1, u2 = nodes[b, 0] - nodes[a, 0], nodes[b, 1] - nodes[a, 1], nodes[b, 2] - nodes[a, 2]
            w0, w1, w2 = nodes[c, 0] - nodes[a, 0], nodes[c, 1] - nodes[a, 1], nodes[c, 2] - nodes[a, 2]
            n0 = u1 * w2 - u2 * w1
            n1 = u2 * w0 - u0 * w2
            n2 = u0 * w1 - u1 * w0
            length = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
            out[j, 0] = n0 / length
            out[j, 1] = n1 / length
            out[j, 2] = n2 / length


def facet_normals(nodes: NDArray[np.float64], facets: NDArray[np.int64]) -> NDArray[np.float64]:
    """Unit outward normals ``(k, d)`` of the facets ``(k, d)`` on ``nodes (m, d)`` (numba)."""
    out = np.empty((facets.shape[0], nodes.shape[1]))
    _normals(np.ascontiguousarray(nodes, dtype=np.float64), np.ascontiguousarray(facets, dtype=np.int64), out)
    return out


def facet_normals_reference(nodes: NDArray[np.float64], facets: NDArray[np.int64]) -> NDArray[np.float64]:
    """Numpy version of :func:`facet_normals`."""
    x = np.asarray(nodes, dtype=float)
    f = np.asarray(facets)
    t = x[f[:, 1]] - x[f[:, 0]]
    if x.shape[1] == 2:
        n = np.column_stack([t[:, 1], -t[:, 0]])
    else:
        n = np.cross(t, x[f[:, 2]] - x[f[:, 0]])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


@dataclass
class ClosestPoints:
    """Closest points of ``n`` point–facet pairs.

    Attributes
    ----------
    weights : (n, d) float array
        Facet coordinates ``N_a`` of the closest point (2D: ``1 − ξ, ξ``; 3D: barycentric).
    region : (n,) int array
        :data:`INTERIOR`, :data:`EDGE` or :data:`VERTEX`.
    points : (n, d) float array
        The closest points ``x_c`` (m).
    normals : (n, d) float array
        The facets' outward unit normals.
    distance : (n,) float array
        Signed distance ``(x − x_c)·n`` (m), negative behind the facet.
    """

    weights: NDArray[np.float64]
    region: NDArray[np.int64]
    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    distance: NDArray[np.float64]


@numba.njit(parallel=True, cache=True)
def _closest_points(x, nodes, facets, normals, facet_of, w_out, reg_out, xc_out, dist_out):
    dim = x.shape[1]
    for i in prange(x.shape[0]):
        j = facet_of[i]
        w0, w1, w2, reg = closest_on_facet(x, i, nodes, facets, j)
        reg_out[i] = reg
        w_out[i, 0] = w0
        w_out[i, 1] = w1
        if dim == 3:
            w_out[i, 2] = w2
        d = 0.0
        for a in range(dim):
            xc = w0 * nodes[facets[j, 0], a] + w1 * nodes[facets[j, 1], a]
            if dim == 3:
                xc += w2 * nodes[facets[j, 2], a]
            xc_out[i, a] = xc
            d += (x[i, a] - xc) * normals[j, a]
        dist_out[i] = d


def closest_points(points: NDArray[np.float64], nodes: NDArray[np.float64], facets: NDArray[np.int64],
                   facet_of: NDArray[np.int64]) -> ClosestPoints:
    """Closest point of each ``points[i] (n, d)`` on the facet ``facet_of[i]`` (numba).

    ``nodes (m, d)`` (m), ``facets (k, d)`` node indices, ``facet_of (n,)`` facet indices.
    """
    x = np.ascontiguousarray(points, dtype=np.float64)
    nd = np.ascontiguousarray(nodes, dtype=np.float64)
    f = np.ascontiguousarray(facets, dtype=np.int64)
    which = np.ascontiguousarray(facet_of, dtype=np.int64)
    n, d = x.shape
    nrm = facet_normals(nd, f)
    w, reg, xc, dist = np.empty((n, d)), np.empty(n, dtype=np.int64), np.empty((n, d)), np.empty(n)
    _closest_points(x, nd, f, nrm, which, w, reg, xc, dist)
    return ClosestPoints(w, reg, xc, nrm[which], dist)


def closest_points_reference(points: NDArray[np.float64], nodes: NDArray[np.float64], facets: NDArray[np.int64],
                             facet_of: NDArray[np.int64]) -> ClosestPoints:
    """Numpy version of :func:`closest_points`, by a different route for triangles: the
    projection onto the plane if its barycentric coordinates are all positive, else the
    nearest of the closest points on the three edges."""
    x = np.asarray(points, dtype=float)
    nd = np.asarray(nodes, dtype=float)
    f = np.asarray(facets)[np.asarray(facet_of)]
    n, d = x.shape
    nrm = facet_normals_reference(nd, f)
    corners = nd[f]  # (n, d, d)

    def on_segment(p, a, b):
        t = b - a
        xi = np.einsum("ij,ij->i", p - a, t) / np.einsum("ij,ij->i", t, t)
        return np.clip(xi, 0.0, 1.0), (xi <= 0.0) | (xi >= 1.0)

    if d == 2:
        xi, clamped = on_segment(x, corners[:, 0], corners[:, 1])
        w = np.column_stack([1.0 - xi, xi])
        reg = np.where(clamped, VERTEX, INTERIOR)
    else:
        a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
        q = x - np.einsum("ij,ij->i", x - a, nrm)[:, None] * nrm  # projection onto the plane
        area = np.einsum("ij,ij->i", np.cross(b - a, c - a), nrm)
        wa = np.einsum("ij,ij->i", np.cross(c - b, q - b), nrm) / area
        wb = np.einsum("ij,ij->i", np.cross(a - c, q - c), nrm) / area
        wc = 1.0 - wa - wb
        w = np.column_stack([wa, wb, wc])
        reg = np.full(n, INTERIOR)
        outside = np.flatnonzero(w.min(axis=1) <= 0.0)
        for i in outside:
            best = None
            for ia, ib in ((0, 1), (1, 2), (0, 2)):
                t, cl = on_segment(x[i:i + 1], corners[i:i + 1, ia], corners[i:i + 1, ib])
                p = (1 - t[0]) * corners[i, ia] + t[0] * corners[i, ib]
                r = float(np.sum((x[i] - p) ** 2))
                if best is None or r < best[0]:
                    ww = np.zeros(3)
                    ww[ia], ww[ib] = 1 - t[0], t[0]
                    best = (r, ww, VERTEX if cl[0] else EDGE)
            w[i], reg[i] = best[1], best[2]
    xc = np.einsum("ia,iad->id", w, corners)
    dist = np.einsum("ij,ij->i", x - xc, nrm)
    return ClosestPoints(w, reg.astype(np.int64), xc, nrm, dist)
