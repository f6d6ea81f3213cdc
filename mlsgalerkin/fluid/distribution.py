r"""How the fluid particles fill space: the geometric volume and the pair-distance statistics.

**Geometric volume.** Each fluid particle stands for the cell
:math:`C_i = [\mathbf x_i - \tfrac12\Delta x,\ \mathbf x_i + \tfrac12\Delta x]^d` of the spacing
:math:`\Delta x` it was built at. The geometric volume (m^d; m² per unit depth in 2D) is the
measure of the union of the cells with the gaps narrower than :data:`CLOSED_GAP` spacings closed:

.. math:: V_\text{geo} = \bigl|\,\operatorname{close}_{g}\bigl(\textstyle\bigcup_i C_i\bigr)\bigr|,

evaluated on a grid of pixels (voxels) of side :math:`\Delta x/k` (:data:`PIXELS_PER_SPACING`):
a pixel belongs to a cell when its centre does. Along each axis the pixel edges sit at the
circular mean phase of the lower cell faces within half a spacing of the lowest one
(:func:`grid_lower_corner`): the flat boundary of a fluid on a floor or against a side wall lies
on pixel edges, and on a lattice so do the others, not on a row of pixel centres where a 10⁻⁹ m
wobble of the particles flips the whole row in or out (a tank 84 cells long read 1.1 % less
volume for one sample when the grid followed one stray particle 0.5 mm below the floor row); the closing is a maximum filter then a minimum
filter over a box of :math:`2r + 1` pixels (it fills every gap up to :math:`2r` pixels wide and
leaves convex shapes as they were), :math:`r = \operatorname{round}((g k - \tfrac12)/2)`
(:func:`closing_radius`). A gap :math:`w\,\Delta x` wide holds :math:`\lfloor wk \rfloor` or
:math:`\lceil wk \rceil` pixels, so the closing's threshold is a pixel wide and set by the
phase: a gap narrower than :math:`(2r + \tfrac12)/k` spacings is closed on average,
:math:`g = 0.625` at :math:`k = 4`, :math:`r = 1` (always below 0.5, never from 0.75 spacings).
(Documented as half a spacing until 2026-12-04.) The threshold is a choice, and it matters where
the fluid is disordered or torn: a lattice jittered by ±0.3 Δx, whose volume is its cells', reads
−0.18 % at 0.625 but −0.98 % with a sharp threshold at 0.5 (32 pixels per spacing), whose
closing leaves its cracks of 0.5–0.6 Δx open; ``beam_clamped``'s torn sheets at 4 mm read
0.3–1.7 % more at 0.625 than at a sharp 0.5 (1.0 % on average over its first 1.45 s). The
pixel-wide threshold also scatters the reading from sample to sample as gaps move through it: a
standard deviation of 0.3–0.4 % against 32 pixels per spacing in those flows (a sample of
``beam_clamped``'s volume error can jump by 0.9 % in a millisecond).
``tests/test_fluid_distribution.py`` measures the threshold. It compares with the
volume the particles' masses and densities say, :math:`\sum_f M_f/\rho_f`; their ratio minus one
is the **volume error**. A fluid that packs tighter than :math:`M/\rho` (pairing, clumping, a
collapsing column) reads a negative error, one that opens voids a positive one.

Measured (``tests/test_fluid_distribution.py``): a lattice block gives :math:`N\Delta x^d`
exactly (its union is a box whose sides are whole numbers of pixels); a lattice jittered by
±0.2 Δx within 1 % (the closing fills the cracks between the cells, up to 0.4 Δx wide; over 60
seeds the mean error is below 0.05 %, its standard deviation 0.18 % for 800 particles in 2D and
0.20 % for 1800 in 3D — the pixel sampling of the ragged boundary —, the largest 0.52 %); a
block of 60 particles along one axis compressed by 10 % along it reads 9.75 % less (its outer
half cells keep their size: :math:`(0.9 \cdot 59 + 1)/60`, within one pixel); an isolated particle
(a splash) its own cell exactly; a disc cut from a lattice its cells exactly (the closing leaves
the one-spacing steps of its boundary open). Cost (one thread, 2 shared cores): 20 000 particles
in a 2D block 5–9 ms, 100 000 in a jittered 3D block 0.13–0.18 s, an 800-particle dam break
spread over a 0.3 m × 0.45 m tank 1.7 ms (the grid spans the particles' bounding box; the
closing, two :mod:`scipy.ndimage` filters over it, is most of the cost): cheap enough for a
time-series row, too dear for every step. :func:`geometric_volume` builds one grid when the
fluid fills a fair share of its bounding box (:data:`SINGLE_GRID_FILL`), and otherwise only the
tiles of :data:`TILE_PIXELS` pixels per side that hold particles (each from the particles within
the closing's reach of it, cropped to them): the count is the same, and a splash flown far from
the bulk costs its own tile. (Tiles of 4096 pixels per side cost 0.2–0.64 s a row in the beam's
run while its splashes were 1–4 m from the bulk, whose tile they shared; 256 pixels cost
3–8 ms.) (One grid
over the whole bounding box had to be coarsened to two pixels per spacing for a dam break on a
beam with four particles fallen 22 m below the tank: its closing then filled gaps a whole spacing
wide, the volume read +17 % and each time-series row cost 1.5–2.3 s instead of 2–3 ms.) The
pixel phase is taken from the lowest *populated* level of faces, so a few splashes below the bulk
do not set it either. :func:`occupancy` (one grid, coarsened above :data:`MAX_PIXELS`) stays for
pictures and tests.

**Where a volume error sits.** :func:`cell_volumes` splits the closed union among the particles,
each pixel to the nearest one (tile by tile, as :func:`geometric_volume` counts them, so the shares
add up to its measure and a splash flown far away costs its own tile), so each particle's share
``v_i`` against its ``M_i/ρ_i`` says where the fluid is looser or tighter than its densities (``verification/volume_attribution.py`` sorts
them by their neighbours; ``docs/theory/stabilisation.md`` §10 has what it found in the splashing
flows). A single share moves by a pixel column with the phase (a quarter of a cell at four pixels
per spacing); sums over a neighbourhood or a class of particles do not:
:func:`neighbourhood_excess` gives each particle the relative excess of its neighbourhood,
``Σ_j (v_j − V_j) / Σ_j V_j`` over itself and the particles within
:data:`NEIGHBOURHOOD_REACH` spacings (the volume consistency's loose side drives its local part
with it).

**Pair statistics.** From the neighbour table (CSR ``indptr``, ``indices``; every pair closer
than the kernel's support is in it): the smallest fluid–fluid pair distance and the number of
fluid–fluid pairs closer than :data:`CLUMP_DISTANCE` spacings (each pair counted once), and the
smallest fluid–wall distance, all in spacings. On a lattice the smallest pair distance is 1 and
no pair is clumped; a fluid at rest keeps it near 0.8–1 (shifting spreads the particles). Pairs
closer than half a spacing are two particles sitting in nearly one cell: the tensile (pairing)
instability or a collapse that the volume error sees as lost volume.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray
from scipy import ndimage
from scipy.spatial import cKDTree

from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period

__all__ = [
    "AT_FLOOR",
    "CLOSED_GAP",
    "CLUMP_DISTANCE",
    "MAX_PIXELS",
    "NEIGHBOURHOOD_REACH",
    "NEIGHBOUR_CLASSES",
    "PIXELS_PER_SPACING",
    "SINGLE_GRID_FILL",
    "SINGLE_GRID_PIXELS",
    "TILE_PIXELS",
    "PairStatistics",
    "cell_volumes",
    "closing_radius",
    "geometric_volume",
    "grid_lower_corner",
    "neighbourhood_excess",
    "occupancy",
    "occupancy_reference",
    "pair_statistics",
    "pair_statistics_reference",
    "volume_error",
    "volume_error_by_class",
]

#: Pixels per spacing ``k`` of the grid the union of cells is measured on.
PIXELS_PER_SPACING = 4
#: Gaps between cells narrower than this many spacings are closed, on average over the pixel
#: phase (:func:`closing_radius`; a lattice jittered by ±0.2 Δx opens cracks up to 0.4 Δx, one
#: jittered by ±0.3 Δx up to 0.6 Δx).
CLOSED_GAP = 0.625
#: The largest grid (pixels or voxels of the bounding box); above it ``k`` is halved (down to 2).
MAX_PIXELS = 40_000_000
#: Pixels per tile side of :func:`geometric_volume`, by dimension (1D, 2D, 3D): 65 536 pixels
#: (2D) or 262 144 voxels (3D) per tile, a few milliseconds each.
TILE_PIXELS = {1: 1 << 16, 2: 256, 3: 64}
#: :func:`geometric_volume` builds one grid over the fluid's bounding box when the box holds no
#: more than this many times the pixels of the particles' cells (or no more than
#: :data:`SINGLE_GRID_PIXELS`), and tiles otherwise.
SINGLE_GRID_FILL = 8
#: A bounding box of up to this many pixels is always one grid.
SINGLE_GRID_PIXELS = 1 << 16
#: The neighbourhood of :func:`neighbourhood_excess`: the particles within this many spacings.
NEIGHBOURHOOD_REACH = 1.5
#: Fluid pairs closer than this many spacings are *clumped*.
CLUMP_DISTANCE = 0.5
#: The classes of :func:`volume_error_by_class`: (name, fewest, most) other fluid particles within
#: :data:`NEIGHBOURHOOD_REACH` spacings (8 inside a square lattice, 5 in a flat free surface, 3 in
#: a chain).
NEIGHBOUR_CLASSES: tuple[tuple[str, int, int], ...] = (
    ("drops", 0, 0), ("sheets and ragged surface", 1, 4), ("surface rows and bulk", 5, 2**62))
#: The class of :func:`volume_error_by_class` across the others: the particles at ``p ≤ 0``, at the
#: cavitation floor (``TaitPressure(negative_pressure="cavitate")`` keeps their density at ``ρ0``,
#: so no density relaxation can give them volume).
AT_FLOOR = "at the cavitation floor"


@numba.njit(cache=True)
def _rasterise(x, origin, pixel, half, shape, grid):
    """Mark the pixels whose centres ``origin + (i + ½) pixel`` lie in a cell ``|c − x| < half``."""
    n, dim = x.shape
    lo = np.zeros(3, dtype=np.int64)
    hi = np.zeros(3, dtype=np.int64)
    for p in range(n):
        for a in range(3):
            lo[a] = 0
            hi[a] = 0
        for a in range(dim):
            # centres c with x − half < c < x + half
            u0 = (x[p, a] - half - origin[a]) / pixel - 0.5
            u1 = (x[p, a] + half - origin[a]) / pixel - 0.5
            i0 = int(math.floor(u0)) + 1
            i1 = int(math.ceil(u1)) - 1
            lo[a] = max(i0, 0)
            hi[a] = min(i1, shape[a] - 1)
        for i in range(lo[0], hi[0] + 1):
            for j in range(lo[1], hi[1] + 1):
                for k in range(lo[2], hi[2] + 1):
                    grid[i, j, k] = 1


def _close(grid: NDArray[np.uint8], size: tuple[int, ...]) -> NDArray[np.uint8]:
    """The closing of ``grid``: a maximum filter then a minimum filter over a box of ``size``
    pixels, zero beyond the grid's edges."""
    return ndimage.minimum_filter(ndimage.maximum_filter(grid, size=size, mode="constant", cval=0),
                                  size=size, mode="constant", cval=0)


def closing_radius(closed_gap: float, pixels_per_spacing: int) -> int:
    """The radius ``r`` (pixels, at least 1) of the closing's box of ``2r + 1`` pixels that closes
    the gaps narrower than ``closed_gap`` spacings on a grid of ``k = pixels_per_spacing`` pixels
    per spacing, on average over the pixel phase: ``r = round((g k − ½)/2)``. The box closes a
    gap of at most ``2r`` pixels, and a gap ``w Δx`` wide holds ``⌊w k⌋`` or ``⌈w k⌉`` pixels,
    so it is closed always below ``2r/k`` spacings, never from ``(2r + 1)/k``, and in a share
    ``2r + 1 − w k`` of the phases between: on average below ``(2r + ½)/k``, which is ``g``
    when ``k = (4r + 1)/(2g)`` (``k = 4``, ``r = 1`` at ``g = 0.625``)."""
    return max(1, round((closed_gap * pixels_per_spacing - 0.5) / 2.0))


def grid_lower_corner(x: NDArray[np.float64], spacing: float, pixel: float) -> NDArray[np.float64]:
    """The lower corner ``(d,)`` (m) of the pixel grid (without its padding) over the cells of
    side ``spacing`` (m) around ``x (n, d)``: at most one ``pixel`` (m) below the lowest cell face
    along each axis, with the pixel edges at the circular mean phase (``face / pixel mod 1``) of
    the lower cell faces of the lowest populated level — the faces within half a spacing of the
    lowest face that has more than ``m = ⌈n^{1/3}⌉`` others within half a spacing above it: the
    particles along a floor or a side wall, not one stray particle nor a few splashes flown below
    the bulk (module docstring)."""
    lower = x - 0.5 * spacing
    low = lower.min(axis=0)
    corner = low.copy()
    n = x.shape[0]
    m = min(n - 1, max(1, math.ceil(n ** (1.0 / 3.0))))
    for a in range(x.shape[1]):
        faces = lower[lower[:, a] <= low[a] + 0.5 * spacing, a]
        if faces.size <= m:            # the lowest face is a stray or a splash: find the lowest populated level
            ordered = np.sort(lower[:, a])
            populated = np.flatnonzero(ordered[m:] - ordered[:-m] <= 0.5 * spacing)
            level = ordered[populated[0]] if populated.size else ordered[0]
            faces = ordered[(ordered >= level) & (ordered <= level + 0.5 * spacing)]
        angle = 2.0 * np.pi * (faces - low[a]) / pixel
        c, s = np.cos(angle).sum(), np.sin(angle).sum()
        if math.hypot(c, s) > 1e-9 * faces.size:
            phase = (math.atan2(s, c) / (2.0 * np.pi)) % 1.0
            corner[a] = low[a] + (phase - 1.0 if phase > 0.0 else 0.0) * pixel   # stays below every face
    return corner


def _closed_grid(x: NDArray[np.float64], spacing: float, pixels_per_spacing: int,
                 closed_gap: float) -> tuple[NDArray[np.uint8], float, NDArray[np.float64]]:
    """:func:`occupancy`'s grid, pixel side (m) and the grid's lower corner ``(3,)`` (m)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    n, dim = x.shape
    k = int(pixels_per_spacing)
    r = closing_radius(closed_gap, k)
    hi = x.max(axis=0) + 0.5 * spacing
    while True:
        pixel = spacing / k
        pad = r + 1
        lo = grid_lower_corner(x, spacing, pixel)
        shape = [int(math.ceil((hi[a] - lo[a]) / pixel)) + 2 * pad for a in range(dim)]
        if k <= 2 or math.prod(shape) <= MAX_PIXELS:
            break
        k //= 2
        r = closing_radius(closed_gap, k)
    origin = np.zeros(3)
    origin[:dim] = lo - pad * pixel
    full = np.ones(3, dtype=np.int64)
    full[:dim] = shape
    grid = np.zeros(tuple(full), dtype=np.uint8)
    _rasterise(x, origin, pixel, 0.5 * spacing, full, grid)
    size = tuple(2 * r + 1 if a < dim else 1 for a in range(3))
    return _close(grid, size), pixel, origin


def occupancy(x: NDArray[np.float64], spacing: float, pixels_per_spacing: int = PIXELS_PER_SPACING,
              closed_gap: float = CLOSED_GAP) -> tuple[NDArray[np.uint8], float]:
    """The closed union of the particles' cells on a pixel grid: ``(grid, pixel)`` with ``grid``
    ``uint8`` of shape ``(m0, m1, m2)`` (1 inside; ``m2 = 1`` in 2D, ``m1 = m2 = 1`` in 1D) and the
    pixel side ``pixel`` (m). ``x (n, d)`` positions (m), ``spacing`` the cell side Δx (m)."""
    grid, pixel, _ = _closed_grid(x, spacing, pixels_per_spacing, closed_gap)
    return grid, pixel


def cell_volumes(x: NDArray[np.float64], spacing: float, pixels_per_spacing: int = PIXELS_PER_SPACING,
                 closed_gap: float = CLOSED_GAP, tile: int | None = None) -> NDArray[np.float64]:
    r"""Each particle's share ``(n,)`` (m^d) of the geometric volume: every pixel of the closed
    union that :func:`geometric_volume` measures goes to the particle nearest its centre (a Voronoi
    split of the union on the pixel grid), so the shares add up to :func:`geometric_volume`'s
    measure, and ``v_i / (M_i/ρ_i) − 1`` says *where* a volume error sits. A particle deep in a
    lattice gets its cell, :math:`\Delta x^d`, exactly; one whose neighbours have moved apart gets
    the closed gaps beside it (a particle of a stretched surface: more than its cell); one that
    shares its cell with a close neighbour, less. ``x (n, d)`` positions (m), ``spacing`` Δx (m).

    The pixels come tile by tile as :func:`geometric_volume`'s (``tile``, the same choice of one
    grid or tiles), so a splash flown far from the bulk costs its own tile, in 3D too; each tile's
    pixels go to their nearest particle among all of them (one :class:`scipy.spatial.cKDTree`)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    n, dim = x.shape
    if n == 0:
        return np.zeros(0)
    tree = cKDTree(x)
    count = np.zeros(n, dtype=np.int64)
    for centres in _closed_pixel_centres(x, spacing, pixels_per_spacing, closed_gap, tile):
        if centres.shape[0]:
            _, owner = tree.query(centres)
            count += np.bincount(owner, minlength=n)
    return count * (spacing / int(pixels_per_spacing)) ** dim


def neighbourhood_excess(x: NDArray[np.float64], shares: NDArray[np.float64], volume: NDArray[np.float64],
                         spacing: float, reach: float = NEIGHBOURHOOD_REACH) -> NDArray[np.float64]:
    r"""The relative volume excess ``(n,)`` (–) of each particle's neighbourhood,

    .. math:: e_i = \frac{\sum_{j \in N_i} (v_j - V_j)}{\sum_{j \in N_i} V_j},

    over the particle itself and those within ``reach`` spacings ``N_i``, with ``v (n,)`` the
    shares of :func:`cell_volumes` and ``V (n,)`` the volumes ``M/ρ`` (m^d each); ``x (n, d)``
    positions (m), ``spacing`` Δx (m). Positive: the neighbourhood stands looser than its volumes
    say. A single share moves by a pixel column with the grid's phase (a quarter of a cell at four
    pixels per spacing); a neighbourhood's sum much less. The pairs come from one
    :class:`scipy.spatial.cKDTree` query."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    n = x.shape[0]
    own = np.asarray(shares, dtype=np.float64) - np.asarray(volume, dtype=np.float64)
    if n == 0:
        return np.zeros(0)
    pairs = cKDTree(x).query_pairs(reach * spacing, output_type="ndarray")
    i = np.concatenate([pairs[:, 0], pairs[:, 1]])
    j = np.concatenate([pairs[:, 1], pairs[:, 0]])
    excess = own + np.bincount(i, weights=own[j], minlength=n)
    return excess / (volume + np.bincount(i, weights=np.asarray(volume, dtype=np.float64)[j], minlength=n))


def volume_error_by_class(x: NDArray[np.float64], volume: NDArray[np.float64], spacing: float, *,
                          at_floor: NDArray[np.bool_] | None = None,
                          shares: NDArray[np.float64] | None = None) -> dict[str, Any]:
    r"""Where a volume error sits: each class of :data:`NEIGHBOUR_CLASSES` (and, with ``at_floor``,
    the particles at the cavitation floor, :data:`AT_FLOOR`, across them) with its share of the
    particles and its **contribution** to the error,

    .. math:: c_\text{class} = \frac{\sum_{i \in \text{class}} (v_i - V_i)}{\sum_i V_i},

    ``v (n,)`` the particles' :func:`cell_volumes` (``shares``; computed when not given), ``V (n,)``
    their ``M/ρ`` (``volume``, m^d), ``x (n, d)`` positions (m), ``spacing`` Δx (m), ``at_floor``
    (bool ``(n,)``). The contributions of :data:`NEIGHBOUR_CLASSES` add up to the error
    ``Σ v / Σ V − 1`` (the shares add up to :func:`geometric_volume`'s measure). Returns
    ``{"volume_error": e, name: {"particles": share, "contribution": c, "excess_per_particle":
    mean of (v − V)/V (NaN for an empty class)}, ...}`` (the floor's entry without the last). One
    :func:`cell_volumes` and one :class:`scipy.spatial.cKDTree` count: 10–20 ms for 1 000 particles
    in 2D, too dear for every step (``verification/volume_attribution.py`` reads it from frames; the
    run checks at the largest readings)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    volume = np.asarray(volume, dtype=np.float64)
    n = x.shape[0]
    total = float(volume.sum())
    if n == 0 or total <= 0.0:
        raise ValueError(f"volume_error_by_class needs particles with a positive total volume, got {n} "
                         f"particles of total volume {total}")
    if shares is None:
        shares = cell_volumes(x, spacing)
    own = np.asarray(shares, dtype=np.float64) - volume
    neighbours = cKDTree(x).query_ball_point(x, NEIGHBOURHOOD_REACH * spacing, return_length=True) - 1
    out: dict[str, Any] = {"volume_error": float(np.sum(shares)) / total - 1.0}
    for name, fewest, most in NEIGHBOUR_CLASSES:
        inside = (neighbours >= fewest) & (neighbours <= most)
        out[name] = {"particles": float(inside.mean()), "contribution": float(own[inside].sum()) / total,
                     "excess_per_particle": float((own[inside] / volume[inside]).mean()) if inside.any()
                     else float("nan")}
    if at_floor is not None:
        floor = np.asarray(at_floor, dtype=bool)
        out[AT_FLOOR] = {"particles": float(floor.mean()), "contribution": float(own[floor].sum()) / total}
    return out


def occupancy_reference(x: NDArray[np.float64], spacing: float, pixels_per_spacing: int = PIXELS_PER_SPACING,
                        closed_gap: float = CLOSED_GAP) -> NDArray[np.uint8]:
    """:func:`occupancy`'s grid with the cells marked by numpy, particle by particle (tests; no
    coarsening)."""
    x = np.asarray(x, dtype=np.float64)
    dim = x.shape[1]
    k = int(pixels_per_spacing)
    r = closing_radius(closed_gap, k)
    pixel = spacing / k
    pad = r + 1
    lo = grid_lower_corner(x, spacing, pixel)
    hi = x.max(axis=0) + 0.5 * spacing
    shape = [int(math.ceil((hi[a] - lo[a]) / pixel)) + 2 * pad for a in range(dim)]
    centres = np.meshgrid(*[lo[a] - pad * pixel + (np.arange(shape[a]) + 0.5) * pixel for a in range(dim)],
                          indexing="ij")
    grid = np.zeros(shape, dtype=bool)
    for p in range(x.shape[0]):   # a test reference: a loop over the particles is fine here
        inside = np.ones(shape, dtype=bool)
        for a in range(dim):
            inside &= np.abs(centres[a] - x[p, a]) < 0.5 * spacing
        grid |= inside
    size = (2 * r + 1,) * dim
    closed = _close(grid.astype(np.uint8), size)
    return closed.reshape(tuple(shape) + (1,) * (3 - dim))


def _tiles(u_lo: NDArray[np.int64], u_hi: NDArray[np.int64], tile: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The tiles each particle's reach ``[u_lo, u_hi]`` (pixel indices, inclusive, ``(n, d)``)
    meets: ``(particle (m,), tile index (m, d))``, one row per particle and tile (``tile`` pixels
    per tile side; a reach meets at most two tiles per axis as it is narrower than a tile)."""
    dim = u_lo.shape[1]
    t_lo = np.floor_divide(u_lo, tile)
    t_hi = np.floor_divide(u_hi, tile)
    owners, keys = [], []
    for corner in range(2 ** dim):                     # the 2^d tile offsets, not a particle loop
        step = np.array([(corner >> a) & 1 for a in range(dim)], dtype=np.int64)
        t = t_lo + step
        ok = np.all(t <= t_hi, axis=1)
        owners.append(np.flatnonzero(ok))
        keys.append(t[ok])
    return np.concatenate(owners), np.concatenate(keys)


def _closed_window(x, u_lo, u_hi, origin, pixel, spacing, r, size, core_lo, tile):
    """The closed union of the cells of ``x`` inside the tile whose first pixel index is
    ``core_lo (d,)`` (all of it when ``core_lo`` is None), on a grid cropped to the cells' reach
    (pixel indices ``u_lo``, ``u_hi``) and padded by ``r + 1`` zero pixels: ``(window, first)``,
    the closed grid's pixels in the tile and the global pixel index ``(d,)`` of its first one."""
    dim = x.shape[1]
    reach = 2 * r + 1
    lo = u_lo.min(axis=0)
    hi = u_hi.max(axis=0)
    if core_lo is not None:
        lo = np.maximum(lo, core_lo - reach)
        hi = np.minimum(hi, core_lo + tile - 1 + reach)
    lo = lo - (r + 1)
    hi = hi + (r + 1)
    shape = np.ones(3, dtype=np.int64)
    shape[:dim] = hi - lo + 1
    local_origin = np.zeros(3)
    local_origin[:dim] = origin + lo * pixel
    grid = np.zeros(tuple(shape), dtype=np.uint8)
    _rasterise(x, local_origin, pixel, 0.5 * spacing, shape, grid)
    grid = _close(grid, size)
    if core_lo is None:
        return grid, lo
    window = [slice(None)] * 3
    start = lo.copy()
    for a in range(dim):
        begin = max(core_lo[a] - lo[a], 0)
        window[a] = slice(begin, max(core_lo[a] + tile - lo[a], 0))
        start[a] = lo[a] + begin
    return grid[tuple(window)], start


def geometric_volume(x: NDArray[np.float64], spacing: float, pixels_per_spacing: int = PIXELS_PER_SPACING,
                     closed_gap: float = CLOSED_GAP, tile: int | None = None) -> float:
    """The geometric volume (m^d; m² per unit depth in 2D) of the particles at ``x (n, d)`` (m),
    each standing for a cell of side ``spacing`` (m): the measure of the union of the cells with
    the gaps up to ``closed_gap`` spacings closed, on a grid of ``spacing / pixels_per_spacing``
    (module docstring). 0 without particles.

    One grid spans the particles' bounding box when it fits a tile, or (``tile=None``) when the
    box holds no more than :data:`SINGLE_GRID_FILL` times the pixels of the particles' cells or
    :data:`SINGLE_GRID_PIXELS` pixels: a compact fluid. Otherwise the grid is cut into tiles of
    ``tile`` pixels per side (default :data:`TILE_PIXELS` for the dimension) and only the tiles
    that hold particles are built, each from the particles whose cells reach within ``2r + 1``
    pixels of it (the closing's reach), cropped to their bounding box, and counted over its own
    pixels: the same count as one grid over the bounding box of all the particles
    (:func:`occupancy`), at the full resolution and a cost set by the fluid's extent, not by how
    far a splash has flown."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.shape[0] == 0:
        return 0.0
    pixel = spacing / int(pixels_per_spacing)
    corner = grid_lower_corner(x, spacing, pixel)
    count = sum(int(np.count_nonzero(window)) for window, _ in _closed_windows(x, spacing, pixels_per_spacing,
                                                                                closed_gap, tile, corner))
    return float(count) * pixel ** x.shape[1]


def _closed_windows(x: NDArray[np.float64], spacing: float, pixels_per_spacing: int, closed_gap: float,
                    tile: int | None, origin: NDArray[np.float64]):
    """The closed union of the cells of ``x (n, d)`` as :func:`geometric_volume` builds it: yields
    ``(window, first)`` per grid, ``window`` the closed grid's ``uint8`` pixels that this grid
    counts (one grid: all of them; a tile: its own) and ``first (d,)`` the global pixel index of
    ``window``'s first pixel (pixel ``u`` has its centre at ``origin + (u + ½) pixel``, ``origin``
    the grid's corner ``(d,)`` (m) of :func:`grid_lower_corner`, which the caller computes once). The
    windows do not overlap, and together they hold the union."""
    dim = x.shape[1]
    k = int(pixels_per_spacing)
    r = closing_radius(closed_gap, k)
    pixel = spacing / k
    automatic = tile is None
    tile = int(TILE_PIXELS[dim] if automatic else tile)
    # pixel indices of each cell's first and last pixel (centres strictly inside the cell; one
    # pixel of slack either way, the rasteriser decides), widened by the closing's reach
    reach = 2 * r + 1
    u = (x - origin) / pixel
    u_lo = np.floor(u - 0.5 * k).astype(np.int64) - 1
    u_hi = np.ceil(u + 0.5 * k).astype(np.int64) + 1
    if tile < (u_hi - u_lo).max() + 2 * reach:
        raise ValueError(f"tile = {tile} pixels is narrower than a cell and the closing's reach "
                         f"({int((u_hi - u_lo).max()) + 2 * reach} pixels); use a larger tile")
    size = tuple(2 * r + 1 if a < dim else 1 for a in range(3))
    span = u_hi.max(axis=0) - u_lo.min(axis=0) + 2 * (r + 2)
    box = float(np.prod(span.astype(float)))
    compact = automatic and box <= max(SINGLE_GRID_FILL * x.shape[0] * float(k) ** dim, SINGLE_GRID_PIXELS)
    if compact or box <= float(tile) ** dim:           # one grid over the whole fluid
        yield _closed_window(x, u_lo, u_hi, origin, pixel, spacing, r, size, None, tile)
        return
    owner, key = _tiles(u_lo - reach, u_hi + reach, tile)
    order = np.lexsort(key.T[::-1])
    owner, key = owner[order], key[order]
    starts = np.flatnonzero(np.r_[True, np.any(key[1:] != key[:-1], axis=1)])
    ends = np.r_[starts[1:], owner.size]
    for a0, a1 in zip(starts, ends):                   # one pass per occupied tile
        members = owner[a0:a1]
        yield _closed_window(x[members], u_lo[members], u_hi[members], origin, pixel, spacing, r, size,
                             key[a0] * tile, tile)


def _closed_pixel_centres(x: NDArray[np.float64], spacing: float, pixels_per_spacing: int, closed_gap: float,
                          tile: int | None):
    """The centres ``(m, d)`` (m) of the closed union's pixels, one array per window of
    :func:`_closed_windows`, written ``base + (u + pad + ½) pixel`` with ``base = corner − pad
    pixel`` and ``pad = r + 1``: the same floating-point numbers as one padded grid over the
    bounding box gives them (so a share does not move with the tiling)."""
    dim = x.shape[1]
    k = int(pixels_per_spacing)
    pixel = spacing / k
    pad = closing_radius(closed_gap, k) + 1
    corner = grid_lower_corner(x, spacing, pixel)
    base = corner - pad * pixel
    for window, first in _closed_windows(x, spacing, pixels_per_spacing, closed_gap, tile, corner):
        inside = np.nonzero(window.reshape(window.shape[:dim]))
        yield np.stack([base[a] + ((inside[a] + (first[a] + pad)) + 0.5) * pixel for a in range(dim)], axis=1)


# --------------------------------------------------------------------------------------
# pair statistics
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PairStatistics:
    """Pair distances of the fluid, in spacings: the smallest fluid–fluid distance
    ``min_pair_distance_dx`` (``inf`` without a fluid pair in the table), the number of
    fluid–fluid pairs closer than the clump distance ``clumped_pairs`` (each pair once), and the
    smallest fluid–wall distance ``min_wall_distance_dx`` (``inf`` without one)."""

    min_pair_distance_dx: float
    clumped_pairs: int
    min_wall_distance_dx: float


@numba.njit(parallel=True, cache=True)
def _pair_rows(indptr, indices, x, n_fluid, clump2, min_ff, clumped, min_fw, period):
    for i in prange(n_fluid):
        best_ff = np.inf
        best_fw = np.inf
        count = 0
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if j == i:
                continue
            d0, d1, d2, r2 = pair_offset(x, i, j, period)
            if j < n_fluid:
                if j > i:   # each fluid pair once
                    if r2 < best_ff:
                        best_ff = r2
                    if r2 < clump2:
                        count += 1
            elif r2 < best_fw:
                best_fw = r2
        min_ff[i] = best_ff
        clumped[i] = count
        min_fw[i] = best_fw


def pair_statistics(indptr: NDArray[np.int64], indices: NDArray[np.int32], x: NDArray[np.float64], n_fluid: int,
                    spacing: float, clump_distance: float = CLUMP_DISTANCE,
                    period: NDArray[np.float64] | None = None) -> PairStatistics:
    """:class:`PairStatistics` of the fluid particles ``0 … n_fluid − 1`` from the neighbour table
    of all particles (fluid first, then walls): CSR ``indptr (n + 1,)``, ``indices (nnz,)`` (a
    symmetric table; only pairs in it are seen), positions ``x (n, d)`` (m), ``spacing`` Δx (m),
    ``clump_distance`` in spacings; ``period (3,)`` (m): minimum-image offsets along the periodic
    axes (default none)."""
    min_ff = np.empty(n_fluid)
    clumped = np.empty(n_fluid, dtype=np.int64)
    min_fw = np.empty(n_fluid)
    _pair_rows(np.ascontiguousarray(indptr), np.ascontiguousarray(indices), np.ascontiguousarray(x), n_fluid,
               (clump_distance * spacing) ** 2, min_ff, clumped, min_fw, as_period(period))
    return _statistics(min_ff, clumped, min_fw, spacing)


def _statistics(min_ff, clumped, min_fw, spacing) -> PairStatistics:
    ff = float(min_ff.min()) if min_ff.size else np.inf
    fw = float(min_fw.min()) if min_fw.size else np.inf
    return PairStatistics(math.sqrt(ff) / spacing, int(clumped.sum()), math.sqrt(fw) / spacing)


def pair_statistics_reference(indptr, indices, x, n_fluid, spacing, clump_distance=CLUMP_DISTANCE) -> PairStatistics:
    """Numpy version of :func:`pair_statistics` (tests)."""
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    cols = np.asarray(indices, dtype=np.int64)
    keep = (rows < n_fluid) & (cols != rows)
    rows, cols = rows[keep], cols[keep]
    d = x[cols] - x[rows]
    r2 = np.zeros(len(rows))
    for a in range(x.shape[1]):    # left to right, as pair_offset sums
        r2 = r2 + d[:, a] * d[:, a]
    ff = (cols < n_fluid) & (cols > rows)
    fw = cols >= n_fluid
    min_ff = np.array([r2[ff].min()]) if ff.any() else np.array([np.inf])
    min_fw = np.array([r2[fw].min()]) if fw.any() else np.array([np.inf])
    clumped = np.array([np.count_nonzero(r2[ff] < (clump_distance * spacing) ** 2)])
    return _statistics(min_ff, clumped, min_fw, spacing)


def volume_error(x: NDArray[np.float64], M: NDArray[np.float64], rho: NDArray[np.float64],
                 spacing: float, rows: NDArray[np.bool_] | None = None) -> tuple[float, float]:
    """The geometric volume ``V_geo`` (m^d) of the particles at ``x (n, d)`` (m; :func:`geometric_volume`)
    and its **volume error** ``V_geo / Σ M/ρ − 1`` (–) against the volume their masses ``M (n,)``
    (kg/m^(3−d)) and densities ``ρ (n,)`` say; ``(0, 0)`` without particles. Positive: the particles
    stand farther apart than their volumes say (voids, a loose packing); negative: tighter.
    ``rows`` (bool ``(n,)``): only these particles."""
    if rows is not None:
        x, M, rho = x[rows], M[rows], rho[rows]
    if x.shape[0] == 0:
        return 0.0, 0.0
    vgeo = geometric_volume(x, spacing)
    return vgeo, vgeo / float(np.sum(M / rho)) - 1.0
