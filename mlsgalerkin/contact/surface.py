r"""The master side of a contact: a surface of facets on nodes, 2D segments or 3D triangles.

A :class:`ContactSurface` holds nodes ``(m, d)`` (m) and facets ``(k, d)`` (node indices):
two end nodes per segment in 2D, three corners per triangle in 3D. The orientation is that of
:class:`mlsgalerkin.dynamics.Surface`: the *outward* normal (pointing away from the body, into
the region where the slave nodes live) is

- 2D: the segment direction ``b − a`` turned clockwise, ``n = (t_y, −t_x)/|t|``;
- 3D: ``n = (b − a) × (c − a)/|…|``, the corners counter-clockwise seen from outside.

So a tank's inner surface has its normals pointing into the tank, where the fluid is. Only the
side a normal points to can be touched (the contact is one-sided; see
:mod:`mlsgalerkin.contact.penalty`).

:func:`surface_points` spreads points evenly over a surface, each standing for a piece of it (its
footprint; the wall particles riding on a structure stand on them): a :class:`SurfacePoints`
along the chains of a 2D surface, a :class:`TrianglePoints` over the triangles of a 3D one.

>>> floor = ContactSurface.polyline([(1.0, 0.0), (0.0, 0.0)])      # right to left: normal up
>>> floor.normals()
array([[0., 1.]])
>>> tank = ContactSurface.tank((0.0, 0.0), (1.0, 0.5))            # open top: 3 segments
>>> (tank.normals() + 0.0).round(12).tolist()
[[-1.0, 0.0], [0.0, 1.0], [1.0, 0.0]]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

__all__ = ["ContactSurface", "SurfacePoints", "TrianglePoints", "surface_chains", "surface_points"]


@dataclass(frozen=True, eq=False)
class ContactSurface:
    """Nodes and oriented facets of a contact surface (see the module docstring).

    Parameters
    ----------
    nodes : (m, d) float array
        Node positions (m), ``d`` = 2 or 3; the reference configuration of a moving wall.
    facets : (k, d) int array
        Node indices of each facet (2D: segments ``a, b``; 3D: triangles ``a, b, c``), ordered
        so that the outward normal points to the side that can be touched.

    Raises ``ValueError`` naming the problem (shape, dimension, non-finite nodes, indices out
    of range, a facet that repeats a node or has zero length or area).
    """

    nodes: NDArray[np.float64]
    facets: NDArray[np.int64]

    def __post_init__(self) -> None:
        x = np.asarray(self.nodes, dtype=float)
        if x.ndim != 2 or x.shape[1] not in (2, 3):
            raise ValueError(f"ContactSurface: nodes must be an (m, 2) or (m, 3) array of positions, got shape {x.shape}")
        if x.shape[0] < x.shape[1]:
            raise ValueError(f"ContactSurface: a {x.shape[1]}D facet needs {x.shape[1]} nodes, got {x.shape[0]}")
        if not np.all(np.isfinite(x)):
            k = int(np.flatnonzero(~np.isfinite(x).all(axis=1))[0])
            raise ValueError(f"ContactSurface: node {k} has a NaN or inf coordinate")
        d = x.shape[1]
        raw = np.asarray(self.facets)
        if raw.ndim != 2 or raw.shape[1] != d or raw.shape[0] == 0:
            kind = "segments (two node indices each)" if d == 2 else "triangles (three node indices each)"
            raise ValueError(f"ContactSurface: {d}D nodes need facets of shape (k, {d}), {kind}, with k >= 1; "
                             f"got shape {raw.shape}")
        if raw.dtype.kind not in "iu" and not (raw.dtype.kind == "f" and np.all(raw == np.round(raw))):
            raise ValueError(f"ContactSurface: facets must be integer node indices, got dtype {raw.dtype}")
        f = raw.astype(np.int64)
        if f.min() < 0 or f.max() >= x.shape[0]:
            raise ValueError(f"ContactSurface: facet node indices must lie in [0, {x.shape[0]}), got "
                             f"{int(f.min())} to {int(f.max())}")
        srt = np.sort(f, axis=1)
        repeated = np.flatnonzero(np.any(srt[:, 1:] == srt[:, :-1], axis=1))
        if repeated.size:
            raise ValueError(f"ContactSurface: facet {int(repeated[0])} repeats a node ({f[repeated[0]].tolist()}); "
                             "each facet joins distinct nodes")
        measure = _measures(x, f)
        scale = float(np.ptp(x, axis=0).max()) or 1.0
        small = np.flatnonzero(measure <= 1e-12 * scale ** (d - 1))
        if small.size:
            what = "length" if d == 2 else "area"
            raise ValueError(f"ContactSurface: facet {int(small[0])} ({f[small[0]].tolist()}) has zero {what}: "
                             "its nodes coincide or are collinear; remove it")
        object.__setattr__(self, "nodes", np.ascontiguousarray(x))
        object.__setattr__(self, "facets", np.ascontiguousarray(f))

    # ------------------------------------------------------------------ sizes
    @property
    def dim(self) -> int:
        """2 or 3."""
        return int(self.nodes.shape[1])

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    @property
    def n_facets(self) -> int:
        return int(self.facets.shape[0])

    def normals(self, nodes: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """Unit outward normals ``(k, d)`` of the facets (at ``nodes`` if given, e.g. moved)."""
        from mlsgalerkin.contact.geometry import facet_normals_reference

        return facet_normals_reference(self.nodes if nodes is None else nodes, self.facets)

    def centroids(self) -> NDArray[np.float64]:
        """Facet centroids ``(k, d)`` (m)."""
        return self.nodes[self.facets].mean(axis=1)

    def measures(self) -> NDArray[np.float64]:
        """Facet lengths (2D, m) or areas (3D, m²), ``(k,)``."""
        return _measures(self.nodes, self.facets)

    def __repr__(self) -> str:
        kind = "segments" if self.dim == 2 else "triangles"
        return f"ContactSurface({self.dim}D, {self.n_nodes} nodes, {self.n_facets} {kind})"

    # ------------------------------------------------------------------ orientation
    def flipped(self) -> ContactSurface:
        """The same facets with the opposite orientation (normals reversed)."""
        f = self.facets.copy()
        f[:, [0, 1]] = f[:, [1, 0]]
        return ContactSurface(self.nodes, f)

    def oriented(self, point: ArrayLike, *, toward: bool = False) -> ContactSurface:
        """Each facet turned so that its normal points away from ``point`` (a point inside the
        body: ``toward=False``) or toward it (a point in the region the slaves fill, e.g. inside
        a tank: ``toward=True``). Decided per facet by the sign of ``(centroid − point)·n``, so
        it is right for a body that is star-shaped about ``point`` (every convex body)."""
        p = np.asarray(point, dtype=float)
        if p.shape != (self.dim,):
            raise ValueError(f"ContactSurface.oriented: point must be a ({self.dim},) position, got shape {p.shape}")
        side = np.einsum("ij,ij->i", self.centroids() - p, self.normals())
        flip = side > 0 if toward else side < 0
        f = self.facets.copy()
        f[flip, 0], f[flip, 1] = self.facets[flip, 1], self.facets[flip, 0]
        return ContactSurface(self.nodes, f)

    # ------------------------------------------------------------------ constructors
    @classmethod
    def polyline(cls, points: ArrayLike, closed: bool = False) -> ContactSurface:
        """2D segments joining consecutive ``points (m, 2)`` (and the last to the first if
        ``closed``). Each normal is its segment's direction turned clockwise: walking along the
        points, the touchable side is on the right. A closed polygon listed clockwise therefore
        faces inward, counter-clockwise outward."""
        x = np.asarray(points, dtype=float)
        if x.ndim != 2 or x.shape[1] != 2:
            raise ValueError(f"ContactSurface.polyline: points must be an (m, 2) array, got shape {x.shape}")
        m = x.shape[0]
        if m < (3 if closed else 2):
            raise ValueError(f"ContactSurface.polyline: need at least {3 if closed else 2} points"
                             f"{' for a closed polygon' if closed else ''}, got {m}")
        idx = np.arange(m)
        facets = np.column_stack([idx, np.roll(idx, -1)]) if closed else np.column_stack([idx[:-1], idx[1:]])
        return cls(x, facets)

    @classmethod
    def tank(cls, lower: ArrayLike, upper: ArrayLike, open_top: bool = True) -> ContactSurface:
        """The inner surface of the box ``[lower, upper]`` (2D or 3D), normals into the box.

        2D: the sides right, floor, left (and the lid unless ``open_top``), one segment each.
        3D: two triangles per face, five faces with ``open_top`` (the top is the face at
        ``upper`` along the last axis, the direction opposite to gravity in the shipped scenes).
        """
        lo = np.asarray(lower, dtype=float)
        hi = np.asarray(upper, dtype=float)
        if lo.shape != hi.shape or lo.ndim != 1 or lo.size not in (2, 3):
            raise ValueError(f"ContactSurface.tank: lower and upper must be (2,) or (3,) points, got {lo.shape} "
                             f"and {hi.shape}")
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi > lo)):
            raise ValueError(f"ContactSurface.tank: need finite lower < upper componentwise, got {lo} and {hi}")
        if lo.size == 2:
            (x0, y0), (x1, y1) = lo, hi
            pts = [(x1, y1), (x1, y0), (x0, y0), (x0, y1)]  # clockwise: the left side faces inward
            return cls.polyline(pts, closed=not open_top)
        corners = np.array([[hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]]
                            for i in range(8)])
        # each face as a quad of corner indices; oriented inward afterwards
        quads = [(0, 1, 3, 2), (0, 1, 5, 4), (0, 2, 6, 4), (1, 3, 7, 5), (2, 3, 7, 6)]
        if not open_top:
            quads.append((4, 5, 7, 6))
        tris = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
        return cls(corners, np.array(tris)).oriented(0.5 * (lo + hi), toward=True)


def _measures(x: NDArray[np.float64], f: NDArray[np.int64]) -> NDArray[np.float64]:
    """Segment lengths (2D) or triangle areas (3D), ``(k,)``."""
    if x.shape[1] == 2:
        return np.linalg.norm(x[f[:, 1]] - x[f[:, 0]], axis=1)
    return 0.5 * np.linalg.norm(np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]]), axis=1)


def surface_chains(segments: NDArray[np.int64]) -> list[NDArray[np.int64]]:
    """The segments of an oriented 2D surface grouped into chains, each in walking order (a
    segment's second node is the next one's first): open chains from their free start, then
    closed loops (started at their lowest segment)."""
    outgoing = {int(a): i for i, a in enumerate(segments[:, 0])}
    has_incoming = {int(b) for b in segments[:, 1]}
    seen = np.zeros(segments.shape[0], dtype=bool)
    chains = []
    starts = [i for i, a in enumerate(segments[:, 0]) if int(a) not in has_incoming]
    for first in starts + list(range(segments.shape[0])):
        if seen[first]:
            continue
        chain, i = [], first
        while i is not None and not seen[i]:
            seen[i] = True
            chain.append(i)
            i = outgoing.get(int(segments[i, 1]))
        chains.append(np.array(chain, dtype=np.int64))
    return chains


@dataclass(frozen=True, eq=False)
class SurfacePoints:
    """Points spread evenly along a 2D surface, each standing for a piece of it.

    Attributes
    ----------
    segment, xi : (n,) arrays
        The segment each point lies on and its position along it (0 at the first node).
    width : (n,) array
        The length of surface each point stands for (m): its *footprint*, centred on it.
    average, start, end : (n, m) sparse matrices
        Linear maps from node values ``(m, ·)`` to the mean over each footprint and to the
        values at its two ends (the surface's piecewise-linear interpolation along its chain).
    """

    segment: NDArray[np.int64]
    xi: NDArray[np.float64]
    width: NDArray[np.float64]
    average: sp.csr_matrix
    start: sp.csr_matrix
    end: sp.csr_matrix

    def kinematics(self, x: NDArray[np.float64], v: NDArray[np.float64]
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Footprint-mean position and velocity ``(n, 2)`` of the surface with node positions
        ``x`` and velocities ``v``, the unit normal of each footprint's chord (the chord from its
        start to its end turned clockwise) and that normal's rate of change ``(n, 2)``."""
        chord = self.end @ x - self.start @ x
        dchord = self.end @ v - self.start @ v
        length = np.sqrt(np.einsum("ij,ij->i", chord, chord))[:, None]
        n = np.stack([chord[:, 1], -chord[:, 0]], axis=1) / length
        dn = np.stack([dchord[:, 1], -dchord[:, 0]], axis=1) / length
        dn -= np.einsum("ij,ij->i", dn, n)[:, None] * n
        return self.average @ x, self.average @ v, n, dn


def _on_chain(cum: NDArray[np.float64], chain_nodes: NDArray[np.int64], s: float) -> list[tuple[int, float]]:
    """The two nodes of a chain (cumulative arc lengths ``cum``) around arc length ``s`` and their
    linear interpolation weights."""
    i = int(np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(chain_nodes) - 2))
    f = (s - cum[i]) / (cum[i + 1] - cum[i])
    return [(int(chain_nodes[i]), 1.0 - f), (int(chain_nodes[i + 1]), f)]


def surface_points(surface: ContactSurface, spacing: float) -> SurfacePoints | TrianglePoints:
    """Points spread evenly over ``surface``, each standing for a piece of it (its footprint).

    2D: along each chain of segments (total length ``S``), ``k = max(1, round(S/spacing))``
    points at arc lengths ``(j + ½) S/k``, each with the footprint ``[s − S/2k, s + S/2k]``
    (a :class:`SurfacePoints`). 3D: each triangle split into ``m²`` equal sub-triangles, one
    point at each one's centroid (a :class:`TrianglePoints`, see :func:`triangle_points`)."""
    if surface.dim == 3:
        return triangle_points(surface, spacing)
    if surface.dim != 2:
        raise ValueError("surface_points: the surface must be 2D or 3D")
    nodes, segs = surface.nodes, surface.facets
    lengths = surface.measures()
    seg_l, xi_l, w_l = [], [], []
    rows_a, rows_s, rows_e = [], [], []          # (point, node, weight) triplets
    count = 0
    for chain in surface_chains(segs):
        chain_nodes = np.concatenate([segs[chain, 0], segs[chain[-1:], 1]])
        cum = np.concatenate([[0.0], np.cumsum(lengths[chain])])
        total = cum[-1]
        k = max(1, int(round(total / spacing)))
        width = total / k
        arc = (np.arange(k) + 0.5) * width
        j = np.clip(np.searchsorted(cum, arc, side="right") - 1, 0, len(chain) - 1)
        seg_l.append(chain[j])
        xi_l.append((arc - cum[j]) / lengths[chain[j]])
        w_l.append(np.full(k, width))

        for q in range(k):
            a, b = arc[q] - 0.5 * width, arc[q] + 0.5 * width
            p = count + q
            rows_s += [(p, n_, w_) for n_, w_ in _on_chain(cum, chain_nodes, a)]
            rows_e += [(p, n_, w_) for n_, w_ in _on_chain(cum, chain_nodes, b)]
            for i in range(len(chain)):                  # mean of the hat functions over [a, b]
                lo, hi = max(a, cum[i]), min(b, cum[i + 1])
                if hi <= lo:
                    continue
                ell = cum[i + 1] - cum[i]
                # ∫ (cum[i+1] − s)/ℓ ds and ∫ (s − cum[i])/ℓ ds over [lo, hi]
                right = ((hi - cum[i]) ** 2 - (lo - cum[i]) ** 2) / (2.0 * ell)
                left = (hi - lo) - right
                rows_a += [(p, chain_nodes[i], left / width), (p, chain_nodes[i + 1], right / width)]
        count += k
    shape = (count, nodes.shape[0])

    def matrix(rows: list) -> sp.csr_matrix:
        r, c, w = (np.array(v) for v in zip(*rows))
        return sp.csr_matrix((w.astype(float), (r.astype(np.int64), c.astype(np.int64))), shape=shape)

    return SurfacePoints(np.concatenate(seg_l), np.concatenate(xi_l), np.concatenate(w_l), matrix(rows_a),
                         matrix(rows_s), matrix(rows_e))


@dataclass(frozen=True, eq=False)
class TrianglePoints:
    r"""Points spread evenly over a 3D surface of triangles, each standing for a piece of it.

    Each triangle ``t`` of area ``A_t`` is split into ``m_t²`` equal sub-triangles, ``m_t =
    max(1, round(√A_t/spacing))`` (the lattice of barycentric step ``1/m_t``: ``m_t(m_t + 1)/2``
    "up" and ``m_t(m_t − 1)/2`` "down" sub-triangles); a point stands at each sub-triangle's
    centroid and its footprint is that sub-triangle, of area ``A_t/m_t²``. The mean of the
    surface's linear interpolation over a sub-triangle is its value at the centroid, so a row of
    ``average`` is the centroid's barycentric weights on the triangle's three nodes (exact).

    The normal of a footprint is its triangle's, from the *current* node positions ``x``:

    .. math:: \mathbf c = (\mathbf x_1 - \mathbf x_0)\times(\mathbf x_2 - \mathbf x_0),\quad
              \mathbf n = \mathbf c/|\mathbf c|,\quad
              \dot{\mathbf n} = (\dot{\mathbf c} - (\dot{\mathbf c}\cdot\mathbf n)\,\mathbf n)/|\mathbf c|,

    with :math:`\dot{\mathbf c} = (\mathbf v_1 - \mathbf v_0)\times(\mathbf x_2 - \mathbf x_0)
    + (\mathbf x_1 - \mathbf x_0)\times(\mathbf v_2 - \mathbf v_0)`, oriented as
    :meth:`ContactSurface.normals` (out of the body). For a rigid motion with angular velocity
    :math:`\boldsymbol\omega`, :math:`\dot{\mathbf n} = \boldsymbol\omega\times\mathbf n`.

    Attributes
    ----------
    triangle : (n,) int array
        The triangle (facet of the surface) each point lies on.
    barycentric : (n, 3) array
        The point's weights on the triangle's three nodes (in facet order; they sum to 1).
    area : (n,) array
        The area of surface each point stands for (m²): its footprint.
    facets : (k, 3) int array
        The surface's triangles (node indices), for the normals.
    average : (n, m) sparse matrix
        The linear map from node values ``(m, ·)`` to the mean over each footprint.

    >>> tri = ContactSurface(np.array([[0.0, 0, 0], [2, 0, 0], [0, 2, 0]]), np.array([[0, 1, 2]]))
    >>> pts = triangle_points(tri, 0.5)          # area 2, m = round(√2/0.5) = 3: 9 points
    >>> float(pts.area.sum()), pts.average.shape, pts.barycentric[0].round(4).tolist()
    (2.0, (9, 3), [0.7778, 0.1111, 0.1111])
    """

    triangle: NDArray[np.int64]
    barycentric: NDArray[np.float64]
    area: NDArray[np.float64]
    facets: NDArray[np.int64]
    average: sp.csr_matrix

    def kinematics(self, x: NDArray[np.float64], v: NDArray[np.float64]
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Footprint-mean position (m) and velocity (m/s) ``(n, 3)`` of the surface with node
        positions ``x (m, 3)`` and velocities ``v (m, 3)``, the unit normal of each footprint's
        triangle and that normal's rate of change (1/s), ``(n, 3)`` (class docstring)."""
        f = self.facets
        e1, e2 = x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]]
        c = np.cross(e1, e2)
        dc = np.cross(v[f[:, 1]] - v[f[:, 0]], e2) + np.cross(e1, v[f[:, 2]] - v[f[:, 0]])
        size = np.sqrt(np.einsum("ij,ij->i", c, c))[:, None]
        n = c / size
        dn = (dc - np.einsum("ij,ij->i", dc, n)[:, None] * n) / size
        t = self.triangle
        return self.average @ x, self.average @ v, n[t], dn[t]


def triangle_points(surface: ContactSurface, spacing: float) -> TrianglePoints:
    """The footprints of the 3D ``surface`` at ``spacing`` (m): ``m²`` equal sub-triangles of each
    triangle, ``m = max(1, round(√A/spacing))``, a point at each centroid (:class:`TrianglePoints`)."""
    if surface.dim != 3:
        raise ValueError("triangle_points: the surface must be 3D (triangles)")
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"triangle_points: spacing must be positive (m), got {spacing!r}")
    areas = surface.measures()
    tri_l, bary_l, area_l = [], [], []
    for t, a in enumerate(areas):
        m = max(1, round(float(np.sqrt(a) / spacing)))
        i, j = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
        up = i + j <= m - 1
        down = i + j <= m - 2
        # centroids (λ1, λ2) of the "up" sub-triangles (i, j), (i+1, j), (i, j+1) and of the
        # "down" ones (i+1, j), (i, j+1), (i+1, j+1), in units of 1/m
        l1 = np.concatenate([i[up] + 1.0 / 3.0, i[down] + 2.0 / 3.0]) / m
        l2 = np.concatenate([j[up] + 1.0 / 3.0, j[down] + 2.0 / 3.0]) / m
        bary_l.append(np.column_stack([1.0 - l1 - l2, l1, l2]))
        tri_l.append(np.full(m * m, t, dtype=np.int64))
        area_l.append(np.full(m * m, a / (m * m)))
    tri = np.concatenate(tri_l)
    bary = np.concatenate(bary_l)
    n = tri.size
    rows = np.repeat(np.arange(n), 3)
    average = sp.csr_matrix((bary.ravel(), (rows, surface.facets[tri].ravel())), shape=(n, surface.n_nodes))
    return TrianglePoints(tri, bary, np.concatenate(area_l), surface.facets.copy(), average)
