r"""Free-surface particle detection: the :class:`FreeSurfaceDetection` effect and its kernels.

Two detectors share one neighbour table (``find_neighbors(x, x, radius=R)`` with
``R >= 2 * radius_factor * spacing``; a larger radius is fine, further pairs are ignored).

**Circle coverage** (2D; Koh et al. 2012, as described by Xing 2019) — :func:`detect_circle_coverage`.
Every particle ``i`` gets a circle of radius :math:`r = 1.05\,r_0` (``r_0`` the initial
spacing) discretised with 360 test points :math:`p_k = x_i + r(\cos\theta_k, \sin\theta_k)`.
The particle is *interior* when every :math:`p_k` lies strictly inside the circle of radius
``r`` of at least one other particle, :math:`|p_k - x_j| < r`; otherwise it is on the free
surface. Only neighbours with :math:`|x_j - x_i| < 2r` can cover anything. An isolated
particle is on the surface.

On a lattice block the test returns exactly the outer ring; a single vacancy is bridged (not a
surface), a cavity two particles wide is detected, and recessed particles of a zigzag surface
are called interior (``docs/theory/galerkin_fluid.md`` §10 has the geometry and the measured
comparison).

**Cheap screen** (any dimension) — :func:`detect_neighbour_deficit`. With
:math:`R_c = 2r` and the weight :math:`w_{ij} = (1 - r_{ij}/R_c)^2` for :math:`r_{ij} < R_c`,

.. math::
    N_i = \#\{j \ne i: r_{ij} < R_c\}, \qquad
    s_i = \frac{\bigl|\sum_j w_{ij} (x_j - x_i)\bigr|}{\sum_j w_{ij} |x_j - x_i|} \in [0, 1].

``s_i`` (the normalised, kernel-weighted offset of the neighbour centroid) is 0 for a
symmetric neighbourhood, 0.43 on a flat lattice surface and 0.77 at a convex lattice corner;
the steep weight makes the half-missing row at ``2 r_0`` under the second row nearly
invisible (``s = 0.003``). Particle ``i`` is on the surface when

* ``N_i < sparse_fraction * N_0`` (default 0.5: isolated particles, filaments and thin sheets,
  whose neighbourhood is symmetric but empty), or
* ``N_i < beta * N_0`` **and** ``s_i > asymmetry_threshold`` (defaults 0.96 and 0.22):
  Xing's (2019) 3D candidate screen :math:`N_p < \beta N_0` followed by the asymmetry test in
  place of the spherical-cap coverage.

``N_0`` is the count of a full neighbourhood: given (``n_reference``, e.g. 12 for a square
lattice at ``R_c = 2.1 r_0``) or the median of ``N_i`` over the particles with
``s_i <= asymmetry_threshold`` (the likely interior, so that a small block whose particles
are mostly on the surface still gets the interior count).

The thresholds were tuned on jittered lattices (``docs/theory/galerkin_fluid.md`` §10);
``verification/free_surface_comparison.py`` regenerates the comparison table.

**Normal-cone scan** (any dimension) — :func:`open_along_normal`: the confirmation step of
Marrone et al. (2010). A particle whose kernel sum is deficient is only a *candidate*: inside a
disordered fluid a particle next to a sparse patch has a kernel sum as low as a surface's
(0.84 at ± 0.25 Δx of jitter against 0.76 on a lattice's top row). The candidate is on the
surface when no neighbour lies in the cone of half-angle π/4 around its outward normal.

The coverage and count detectors are numba loops parallel over particles, the cone scan a
serial one (its candidates are few); each has a numpy reference
(:func:`detect_circle_coverage_reference`, :func:`surface_indicators_reference`).

Example
-------
>>> import numpy as np
>>> from mlsgalerkin.neighbors import find_neighbors
>>> g = np.arange(5.0)
>>> x = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
>>> table = find_neighbors(x, x, radius=2.2)
>>> surface = detect_free_surface(x, table, spacing=1.0)
>>> int(surface.sum()), bool(surface[12])  # the 16 particles of the outer ring; centre inside
(16, False)
>>> bool(np.array_equal(surface, detect_free_surface(x, table, 1.0, method="cheap")))
True
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numba import prange
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.fluid.effect import Effect, EffectContext
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period, minimum_image
from mlsgalerkin.neighbors import NeighborTable, as_coordinates

__all__ = [
    "FreeSurfaceDetection",
    "detect_circle_coverage",
    "detect_circle_coverage_reference",
    "detect_free_surface",
    "detect_neighbour_deficit",
    "open_along_normal",
    "open_along_normal_reference",
    "surface_indicators",
    "surface_indicators_reference",
]

BoolArray = NDArray[np.bool_]
FloatArray = NDArray[np.float64]

_CHUNK = 64


# --------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------


def _check_inputs(
    positions: ArrayLike, neighbors: NeighborTable, spacing: float, radius_factor: float
):
    x = as_coordinates("positions", positions)
    n = x.shape[0]
    if not isinstance(neighbors, NeighborTable):
        raise ValueError(f"neighbors must be a NeighborTable, got {type(neighbors).__name__}")
    if neighbors.n_points != n or neighbors.n_nodes != n:
        raise ValueError(
            f"neighbors must be the table of the particles against themselves: expected "
            f"{n} points and {n} nodes, got {neighbors.n_points} points and "
            f"{neighbors.n_nodes} nodes"
        )
    spacing = float(spacing)
    if not (math.isfinite(spacing) and spacing > 0):
        raise ValueError(
            f"spacing (the initial particle spacing r0) must be positive, got {spacing}"
        )
    radius_factor = float(radius_factor)
    if not (math.isfinite(radius_factor) and radius_factor > 0):
        raise ValueError(f"radius_factor must be positive, got {radius_factor}")
    indptr = np.ascontiguousarray(neighbors.indptr, dtype=np.int64)
    indices = np.ascontiguousarray(neighbors.indices, dtype=np.int32)
    return x, indptr, indices, spacing * radius_factor


def _test_directions(n_test_points: int) -> FloatArray:
    n_test_points = int(n_test_points)
    if n_test_points < 3:
        raise ValueError(f"n_test_points must be at least 3, got {n_test_points}")
    theta = 2.0 * np.pi * np.arange(n_test_points) / n_test_points
    return np.ascontiguousarray(np.stack([np.cos(theta), np.sin(theta)], axis=1))


# --------------------------------------------------------------------------------------
# circle coverage (2D)
# --------------------------------------------------------------------------------------


@numba.njit(parallel=True, cache=True)
def _circle_coverage_kernel(x, indptr, indices, radius, dirs, period):
    n = x.shape[0]
    nt = dirs.shape[0]
    r2 = radius * radius
    reach2 = 4.0 * r2
    max_row = 0
    for i in range(n):
        max_row = max(max_row, indptr[i + 1] - indptr[i])
    out = np.zeros(n, dtype=np.bool_)
    n_chunks = (n + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        rel = np.empty((max(max_row, 1), 2))
        for i in range(c * _CHUNK, min(n, (c + 1) * _CHUNK)):
            m = 0
            for p in range(indptr[i], indptr[i + 1]):
                j = indices[p]
                if j == i:
                    continue
                dx, dy, _, rr = pair_offset(x, i, j, period)
                if rr < reach2:
                    rel[m, 0] = dx
                    rel[m, 1] = dy
                    m += 1
            if m == 0:
                out[i] = True
                continue
            last = 0  # the neighbour that covered the previous test point is tried first
            for k in range(nt):
                px = radius * dirs[k, 0]
                py = radius * dirs[k, 1]
                covered = False
                for t in range(m):
                    q = last + t
                    if q >= m:
                        q -= m
                    ex = px - rel[q, 0]
                    ey = py - rel[q, 1]
                    if ex * ex + ey * ey < r2:
                        covered = True
                        last = q
                        break
                if not covered:
                    out[i] = True
                    break
    return out


def detect_circle_coverage(
    positions: ArrayLike,
    neighbors: NeighborTable,
    spacing: float,
    radius_factor: float = 1.05,
    n_test_points: int = 360,
    period: ArrayLike | None = None,
) -> BoolArray:
    """Free-surface flags by the 2D circle-coverage test, ``(n,)`` bool (True = surface).

    Parameters
    ----------
    positions : (n, 2) float, m.
    neighbors : the table of the particles against themselves (``find_neighbors(x, x, R)``)
        with ``R >= 2 * radius_factor * spacing``; the pair ``(i, i)`` may be present.
    spacing : initial particle spacing ``r0``, m.
    radius_factor : circle radius ``r = radius_factor * r0`` (Koh et al. 2012: 1.05).
    n_test_points : points on each circle, evenly spaced from angle 0 (Koh et al. 2012: 360).
    period : optional (3,) periods (m) of the periodic axes, 0 for the others (minimum-image offsets).
    """
    x, indptr, indices, radius = _check_inputs(positions, neighbors, spacing, radius_factor)
    if x.shape[1] != 2:
        raise ValueError(
            f"the circle-coverage test is two-dimensional; positions have dimension {x.shape[1]}. "
            "Use method='cheap' (detect_neighbour_deficit) in other dimensions"
        )
    return _circle_coverage_kernel(x, indptr, indices, radius, _test_directions(n_test_points), as_period(period))


def detect_circle_coverage_reference(
    positions: ArrayLike,
    neighbors: NeighborTable,
    spacing: float,
    radius_factor: float = 1.05,
    n_test_points: int = 360,
) -> BoolArray:
    """numpy reference of :func:`detect_circle_coverage` (all pairs × all test points at once)."""
    from scipy.sparse import csr_array

    x, indptr, indices, radius = _check_inputs(positions, neighbors, spacing, radius_factor)
    if x.shape[1] != 2:
        raise ValueError("the circle-coverage test is two-dimensional")
    dirs = _test_directions(n_test_points)
    n = x.shape[0]
    rows = np.repeat(np.arange(n), np.diff(indptr))
    cols = indices.astype(np.int64)
    dx = x[cols, 0] - x[rows, 0]
    dy = x[cols, 1] - x[rows, 1]
    r2 = radius * radius
    keep = (cols != rows) & (dx * dx + dy * dy < 4.0 * r2)
    rows, dx, dy = rows[keep], dx[keep], dy[keep]
    ex = (radius * dirs[:, 0])[None, :] - dx[:, None]
    ey = (radius * dirs[:, 1])[None, :] - dy[:, None]
    inside = (ex * ex + ey * ey < r2).astype(np.float64)  # (n_pairs, n_test_points)
    select = csr_array((np.ones(rows.size), (rows, np.arange(rows.size))), shape=(n, rows.size))
    covered = (select @ inside) > 0
    return ~covered.all(axis=1)


# --------------------------------------------------------------------------------------
# cheap screen (any dimension)
# --------------------------------------------------------------------------------------


@numba.njit(parallel=True, cache=True)
def _indicator_kernel(x, indptr, indices, cutoff, period):
    n, dim = x.shape
    counts = np.zeros(n, dtype=np.int64)
    asym = np.ones(n)
    c2 = cutoff * cutoff
    for i in prange(n):
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        norm = 0.0
        cnt = 0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            if j == i:
                continue
            d0, d1, d2, rr = pair_offset(x, i, j, period)   # x_ji = x_j − x_i
            if rr >= c2:
                continue
            r = math.sqrt(rr)
            a = 1.0 - r / cutoff
            w = a * a
            s0 += w * d0
            s1 += w * d1
            s2 += w * d2
            norm += w * r
            cnt += 1
        counts[i] = cnt
        if norm > 0.0:
            asym[i] = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2) / norm
    return counts, asym


def surface_indicators(
    positions: ArrayLike,
    neighbors: NeighborTable,
    spacing: float,
    radius_factor: float = 1.05,
    period: ArrayLike | None = None,
) -> tuple[NDArray[np.int64], FloatArray]:
    """Neighbour count ``N_i`` and asymmetry ``s_i`` of the cheap screen (module docstring).

    Returns ``(counts (n,) int64, asymmetry (n,) float in [0, 1])``, counting neighbours
    ``j != i`` with ``|x_j - x_i| < R_c = 2 * radius_factor * spacing``; ``s_i = 1`` for a
    particle without neighbours. Any dimension 1–3. ``period (3,)`` m: minimum-image offsets
    along the periodic axes (default none).
    """
    x, indptr, indices, radius = _check_inputs(positions, neighbors, spacing, radius_factor)
    return _indicator_kernel(x, indptr, indices, 2.0 * radius, as_period(period))


def surface_indicators_reference(
    positions: ArrayLike,
    neighbors: NeighborTable,
    spacing: float,
    radius_factor: float = 1.05,
    period: ArrayLike | None = None,
) -> tuple[NDArray[np.int64], FloatArray]:
    """numpy reference of :func:`surface_indicators`."""
    x, indptr, indices, radius = _check_inputs(positions, neighbors, spacing, radius_factor)
    n, dim = x.shape
    cutoff = 2.0 * radius
    rows = np.repeat(np.arange(n), np.diff(indptr))
    cols = indices.astype(np.int64)
    d = minimum_image(x[cols] - x[rows], as_period(period))
    r = np.sqrt(np.einsum("pd,pd->p", d, d))
    keep = (cols != rows) & (r < cutoff)
    rows, d, r = rows[keep], d[keep], r[keep]
    w = (1.0 - r / cutoff) ** 2
    counts = np.bincount(rows, minlength=n).astype(np.int64)
    s = np.stack([np.bincount(rows, w * d[:, a], minlength=n) for a in range(dim)], axis=1)
    norm = np.bincount(rows, w * r, minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        asym = np.where(norm > 0, np.linalg.norm(s, axis=1) / np.where(norm > 0, norm, 1.0), 1.0)
    return counts, asym


def detect_neighbour_deficit(
    positions: ArrayLike,
    neighbors: NeighborTable,
    spacing: float,
    *,
    radius_factor: float = 1.05,
    n_reference: float | None = None,
    beta: float = 0.96,
    asymmetry_threshold: float = 0.22,
    sparse_fraction: float = 0.5,
    period: ArrayLike | None = None,
) -> BoolArray:
    """Free-surface flags by the cheap count + asymmetry screen, ``(n,)`` bool, any dimension.

    Surface iff ``N_i < sparse_fraction * N_0`` or (``N_i < beta * N_0`` and
    ``s_i > asymmetry_threshold``), with ``N_i``, ``s_i`` from :func:`surface_indicators` and
    ``N_0 = n_reference`` or, if omitted, the median of ``N_i`` over the particles with
    ``s_i <= asymmetry_threshold`` (the maximum count if there are none). See the module
    docstring for the choice of the defaults. ``positions`` (n, d) in m, ``spacing`` = ``r0`` in m;
    ``period (3,)`` m: minimum-image offsets along the periodic axes (default none).
    """
    if not 0.0 < float(beta) <= 2.0:
        raise ValueError(f"beta must be in (0, 2], got {beta}")
    if not 0.0 <= float(asymmetry_threshold) < 1.0:
        raise ValueError(f"asymmetry_threshold must be in [0, 1), got {asymmetry_threshold}")
    if not 0.0 <= float(sparse_fraction) <= float(beta):
        raise ValueError(f"sparse_fraction must be in [0, beta], got {sparse_fraction}")
    counts, asym = surface_indicators(positions, neighbors, spacing, radius_factor, period)
    if n_reference is None:
        calm = asym <= asymmetry_threshold  # the likely interior
        n0 = float(np.median(counts[calm])) if calm.any() else float(counts.max())
        n0 = max(n0, 1.0)
    else:
        n0 = float(n_reference)
        if not (math.isfinite(n0) and n0 > 0):
            raise ValueError(f"n_reference must be a positive neighbour count, got {n_reference}")
    sparse = counts < sparse_fraction * n0
    candidate = counts < beta * n0
    return sparse | (candidate & (asym > asymmetry_threshold))


#: Half-angle of the cone of :func:`open_along_normal` (rad): Marrone et al.'s (2010) π/4.
CONE_HALF_ANGLE = math.pi / 4


@numba.njit(cache=True)
def _open_cone_kernel(x, indptr, indices, candidates, normals, cos_cone, period, out):
    # serial: the candidates are the few particles with a deficient kernel sum, and a thread
    # launch would cost more than the scan
    for k in range(candidates.shape[0]):
        i = candidates[k]
        is_open = True
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if j == i:
                continue
            d0, d1, d2, r2 = pair_offset(x, i, j, period)
            along = d0 * normals[k, 0]
            if x.shape[1] > 1:
                along += d1 * normals[k, 1]
            if x.shape[1] > 2:
                along += d2 * normals[k, 2]
            if r2 > 0.0 and along > cos_cone * math.sqrt(r2):
                is_open = False
                break
        out[k] = is_open


def open_along_normal(positions: ArrayLike, neighbors: NeighborTable, candidates: ArrayLike, normals: ArrayLike,
                      half_angle: float = CONE_HALF_ANGLE, period: ArrayLike | None = None) -> BoolArray:
    r"""Whether each candidate's outward cone is empty, ``(m,)`` bool: the scan-region step of
    Marrone et al. (2010), which confirms a free-surface candidate found by a deficient kernel sum.

    Candidate ``i`` (with unit outward normal :math:`\mathbf n_i`) is *covered* when a neighbour
    ``j`` of its row lies inside the cone of half-angle ``half_angle`` (default π/4) around
    :math:`\mathbf n_i`, :math:`(\mathbf x_j - \mathbf x_i)\cdot\mathbf n_i > \cos(\text{half\_angle})\,
    |\mathbf x_j - \mathbf x_i|`, and *open* (on the surface) otherwise. A particle of a
    disordered interior whose kernel sum is low because its neighbours are sparse has
    neighbours in every direction and is covered; a particle of a free surface has none above
    it. The rows of ``neighbors`` may hold wall particles: a wall inside the cone covers too.

    Parameters
    ----------
    positions : (n, d) float, m.
    neighbors : the CSR table whose row ``i`` lists the neighbours of particle ``i`` (any radius:
        the cone reaches as far as the row does).
    candidates : (m,) int, the particles to test.
    normals : (m, d) float, their unit outward normals.
    half_angle : the cone's half-angle (rad), in (0, π/2].
    period : (3,) float, the periodic lengths (m; 0 for none).
    """
    # called on every force evaluation: shape checks only (a full finiteness check of every
    # position would cost more than the scan)
    x = np.ascontiguousarray(positions, dtype=np.float64)
    if x.ndim != 2 or not 1 <= x.shape[1] <= 3:
        raise ValueError(f"positions must have shape (n, d) with d = 1, 2 or 3, got {x.shape}")
    cand = np.ascontiguousarray(candidates, dtype=np.int64).ravel()
    nrm = np.ascontiguousarray(normals, dtype=np.float64).reshape(cand.shape[0], x.shape[1])
    if not 0.0 < half_angle <= math.pi / 2:
        raise ValueError(f"half_angle must be in (0, pi/2] rad, got {half_angle!r}")
    out = np.empty(cand.shape[0], dtype=np.bool_)
    if cand.shape[0] == 0:
        return out
    _open_cone_kernel(x, np.ascontiguousarray(neighbors.indptr, dtype=np.int64), np.ascontiguousarray(neighbors.indices),
                      cand, nrm, math.cos(half_angle), as_period(period), out)
    return out


def open_along_normal_reference(positions: ArrayLike, neighbors: NeighborTable, candidates: ArrayLike,
                                normals: ArrayLike, half_angle: float = CONE_HALF_ANGLE,
                                period: ArrayLike | None = None) -> BoolArray:
    """numpy reference of :func:`open_along_normal`."""
    x = as_coordinates("positions", positions)
    cand = np.asarray(candidates, dtype=np.int64)
    nrm = np.asarray(normals, dtype=np.float64).reshape(cand.shape[0], x.shape[1])
    out = np.ones(cand.shape[0], dtype=bool)
    for k, i in enumerate(cand):
        j = neighbors.indices[neighbors.indptr[i]:neighbors.indptr[i + 1]].astype(np.int64)
        j = j[j != i]
        off = minimum_image(x[j] - x[i], as_period(period))
        r = np.sqrt(np.einsum("pd,pd->p", off, off))
        out[k] = not np.any((r > 0) & (off @ nrm[k] > math.cos(half_angle) * r))
    return out


def detect_free_surface(
    positions: ArrayLike,
    neighbors: NeighborTable,
    spacing: float,
    method: str = "circle",
    **options,
) -> BoolArray:
    """Free-surface flags ``(n,)`` bool by ``method="circle"`` (2D, :func:`detect_circle_coverage`)
    or ``"cheap"`` (any dimension, :func:`detect_neighbour_deficit`); ``options`` go to the method.
    """
    if method == "circle":
        return detect_circle_coverage(positions, neighbors, spacing, **options)
    if method == "cheap":
        return detect_neighbour_deficit(positions, neighbors, spacing, **options)
    raise ValueError(f"unknown free-surface method {method!r}; choose 'circle' or 'cheap'")


# --------------------------------------------------------------------------------------
# the effect
# --------------------------------------------------------------------------------------


class FreeSurfaceDetection(Effect):
    """Flags free-surface particles every ``every`` steps into ``s.extra["free_surface"]``.

    ``method="circle"``: the 2D 360-point circle-coverage test (Koh et al. 2012; radius
    1.05 Δx); ``method="cheap"``: the neighbour-deficit screen (:func:`detect_neighbour_deficit`).
    The Galerkin weak form needs no surface condition (traction-free is natural); the flags
    serve output and diagnostics. Provides ``free_surface``.
    """

    name = "free_surface"
    stages = ("after_step",)
    reads = ("positions", "neighbors")
    provides = ("free_surface",)

    def __init__(self, method: str = "circle", every: int = 10) -> None:
        self.method, self.every = method, every
        self.count = 0

    def __repr__(self) -> str:
        return f"FreeSurfaceDetection(method={self.method!r}, every={self.every})"

    def check(self, ctx: EffectContext) -> list[str]:
        problems = []
        if self.method not in ("circle", "cheap"):
            problems.append(f"FreeSurfaceDetection: method must be 'circle' or 'cheap', got {self.method!r}")
        if self.method == "circle" and ctx.dim != 2:
            problems.append("FreeSurfaceDetection: the circle-coverage test is 2D; use method='cheap' in 3D")
        return problems

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        state.extra["free_surface"] = np.zeros(state.n, dtype=bool)

    def after_step(self, s: FluidState) -> None:
        if s.step % self.every and s.step > 1:
            return
        flags = detect_free_surface(s.x, s.neighbors, s.spacing, method=self.method, period=s.period)
        flags[s.walls] = False
        s.extra["free_surface"] = flags
        self.count = int(np.count_nonzero(flags))

    def summary(self) -> dict[str, Any]:
        return {"method": self.method, "last_count": self.count}
