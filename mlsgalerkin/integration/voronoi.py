"""Voronoi cells of 2D nodes clipped to a convex polygonal domain (nodal volumes, SCNI cells).

The nodes are mirrored across every domain edge so that each original node's Voronoi cell is
bounded, then each cell is clipped to the domain (Sutherland–Hodgman). Cells are returned as
counter-clockwise vertex arrays.

>>> import numpy as np
>>> from mlsgalerkin.integration.voronoi import rectangle, voronoi_volumes
>>> x = np.array([[0.25, 0.5], [0.75, 0.5], [0.5, 0.9]])
>>> float(voronoi_volumes(x, rectangle((0, 0), (1, 1))).sum())
1.0
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["rectangle", "polygon_area", "check_domain", "clipped_voronoi_cells", "voronoi_volumes"]


def rectangle(lower: ArrayLike, upper: ArrayLike) -> NDArray[np.float64]:
    """Counter-clockwise corners ``(4, 2)`` of an axis-aligned rectangle."""
    (x0, y0), (x1, y1) = np.asarray(lower, float), np.asarray(upper, float)
    if not (x1 > x0 and y1 > y0):
        raise ValueError(f"rectangle needs lower < upper, got {lower} and {upper}")
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])


def polygon_area(poly: NDArray[np.float64]) -> float:
    """Signed area (shoelace), positive for counter-clockwise vertices."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def check_domain(domain: ArrayLike) -> NDArray[np.float64]:
    """``domain`` as a ``(n_corners, 2)`` float array, after checking it is a convex CCW polygon.

    Raises ``ValueError`` for fewer than 3 corners, clockwise order or a non-convex corner
    (the clipping and the boundary quadrature assume a convex counter-clockwise polygon).
    """
    d = np.asarray(domain, dtype=float)
    if d.ndim != 2 or d.shape[1] != 2 or d.shape[0] < 3:
        raise ValueError(f"domain must be a (n_corners >= 3, 2) polygon, got shape {d.shape}")
    if polygon_area(d) <= 0:
        raise ValueError("domain corners must be listed counter-clockwise")
    e = np.roll(d, -1, axis=0) - d
    cross = e[:, 0] * np.roll(e, -1, axis=0)[:, 1] - e[:, 1] * np.roll(e, -1, axis=0)[:, 0]
    if (cross < -1e-12 * np.abs(e).max() ** 2).any():
        raise ValueError("domain must be convex (clipping uses Sutherland–Hodgman)")
    return d


def _clip(poly: NDArray, a: NDArray, b: NDArray) -> NDArray:
    """Keep the part of ``poly`` left of the directed line a→b."""
    if poly.shape[0] == 0:
        return poly
    n = np.array([b[1] - a[1], a[0] - b[0]])  # outward normal of a CCW edge
    s = (poly - a) @ n  # > 0 outside
    out = []
    m = poly.shape[0]
    for k in range(m):
        p, q = poly[k], poly[(k + 1) % m]
        sp, sq = s[k], s[(k + 1) % m]
        if sp <= 0:
            out.append(p)
        if (sp < 0 < sq) or (sq < 0 < sp):
            t = sp / (sp - sq)
            out.append(p + t * (q - p))
    return np.array(out).reshape(-1, 2)


def clipped_voronoi_cells(nodes: ArrayLike, domain: ArrayLike) -> list[NDArray[np.float64]]:
    """Voronoi cell of each node clipped to a convex ``domain``; list of ``(k, 2)`` CCW arrays."""
    from scipy.spatial import Voronoi

    x = np.asarray(nodes, dtype=float)
    if x.ndim != 2 or x.shape[1] != 2:
        raise ValueError(f"clipped Voronoi cells are 2D: nodes must be (n, 2), got {x.shape}")
    dom = check_domain(domain)
    if len(np.unique(x, axis=0)) != len(x):
        raise ValueError("nodes contain duplicates; a Voronoi diagram needs distinct nodes")
    mirrors = [x]
    for k in range(dom.shape[0]):
        a, b = dom[k], dom[(k + 1) % dom.shape[0]]
        t = (b - a) / np.linalg.norm(b - a)
        rel = x - a
        mirrors.append(a + 2 * np.outer(rel @ t, t) - rel)
    vor = Voronoi(np.vstack(mirrors))
    cells = []
    for i in range(x.shape[0]):
        region = vor.regions[vor.point_region[i]]
        if -1 in region or not region:
            raise RuntimeError(f"Voronoi cell of node {i} is unbounded; is the node inside the domain?")
        poly = vor.vertices[region]
        c = poly.mean(axis=0)
        poly = poly[np.argsort(np.arctan2(poly[:, 1] - c[1], poly[:, 0] - c[0]))]
        for k in range(dom.shape[0]):
            poly = _clip(poly, dom[k], dom[(k + 1) % dom.shape[0]])
        if poly.shape[0] < 3:
            raise ValueError(f"node {i} at {x[i].tolist()} lies outside the domain")
        cells.append(poly)
    return cells


def voronoi_volumes(nodes: ArrayLike, domain: ArrayLike) -> NDArray[np.float64]:
    """Areas of the clipped Voronoi cells, ``(n,)``; they sum to the domain area."""
    return np.array([polygon_area(c) for c in clipped_voronoi_cells(nodes, domain)])
