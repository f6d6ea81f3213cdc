r"""Wall penetration: how far fluid particles have crossed the surface of the walls.

A wall body's particles stand in layers behind its surface, the first layer half a spacing
from it (``wall_box`` builds them so). Each wall particle ``w`` knows its offset behind the
surface, :math:`o_w = (k_w + \tfrac12)\,\Delta x_w` for layer :math:`k_w` (the number of
particles of its body in front of it along its normal :math:`\mathbf n_w`, counted once from
the initial geometry by :func:`surface_offsets`). A fluid particle ``f`` whose nearest wall
particle (among its neighbours) is ``w``, at the offset :math:`\mathbf r = \mathbf x_f - \mathbf x_w`,
lies

.. math:: \delta_f = o_w - \mathbf r\cdot\mathbf n_w

*behind* the wall surface; :math:`\delta_f > 0` is a penetration **where the wall is**: only
when ``f`` lies in the cell of ``w``, not beyond the back of it,
:math:`\mathbf r\cdot\mathbf n_w \ge -\tfrac12\Delta x`, and not beside it, every world
component of the tangential offset :math:`\mathbf t = \mathbf r - (\mathbf r\cdot\mathbf n_w)
\mathbf n_w` within :math:`\tfrac12\Delta x` (:data:`CELL_TOLERANCE` added for rounding). The
cells of a wall's particles tile the wall, so a particle inside the wall is in the cell of its
nearest wall particle; water passing over the top of an open tank's end wall (beside the cell
of the top wall particle) or falling down the wall's outer face (beyond the back of its last
layer) is not inside the wall, and the half-space test without these bounds counted it as up
to 5 spacings "behind" the wall. :func:`penetration_depths` returns :math:`\max(\delta_f, 0)`
per fluid particle (0 without a wall neighbour). The fluid
solver records after every step the number of penetrating particles and the deepest
penetration in units of the spacing (time-series columns ``wall_penetrations`` and
``max_wall_penetration_dx``; ``summary.json`` keeps the largest over the run) and warns once
when a particle is more than :data:`PENETRATION_WARNING` spacings behind a wall: it has passed
the first layer of wall particles, and the wall no longer holds the fluid there. At corners
(diagonal normals) the offset is that of the first layer. Wall particles riding on a structure
are not measured here (their offset is ``−inf``): a structure is thin and has corners, where
this half-space test counted the water passing the gate of ``elastic_gate`` as up to two
spacings behind it; the coupling's penalty contact measures the penetration into a structure
against its exact surface (``max_penetration_m`` in ``summary.json``; at most 1.8e-5 m there).
"""

from __future__ import annotations

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period

__all__ = ["CELL_TOLERANCE", "PENETRATION_WARNING", "penetration_depths", "penetration_depths_reference",
           "surface_offsets"]

#: Depth (in spacings) beyond which a penetration is warned about: past the first wall layer.
PENETRATION_WARNING = 0.5
#: Added to the half spacing of a wall particle's cell (in spacings): a particle midway between
#: two wall particles is in both cells up to rounding.
CELL_TOLERANCE = 1e-6


def surface_offsets(positions: NDArray[np.float64], normals: NDArray[np.float64], spacing: float
                    ) -> NDArray[np.float64]:
    """Offset ``(k + 1/2) Δx`` of each wall particle of one body behind the body's surface (m):
    ``k`` counts the particles of the body found one, two, … spacings in front of it along its
    normal (within a quarter spacing)."""
    from scipy.spatial import cKDTree

    n = positions.shape[0]
    if n == 0:
        return np.zeros(0)
    tree = cKDTree(positions)
    layer = np.zeros(n, dtype=np.int64)
    active = np.ones(n, dtype=bool)
    for m in range(1, 64):
        probe = positions + m * spacing * normals
        dist, _ = tree.query(probe, distance_upper_bound=0.25 * spacing)
        hit = active & np.isfinite(dist)
        layer[hit] += 1
        active &= hit
        if not active.any():
            break
    return (layer + 0.5) * spacing


@numba.njit(parallel=True, cache=True)
def _depths(indptr, indices, x, n_fluid, normals, offsets, half, out, period):
    dim = x.shape[1]
    for i in prange(n_fluid):
        best = np.inf
        depth = 0.0
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if j < n_fluid:
                continue
            w = j - n_fluid
            d0, d1, d2, r2 = pair_offset(x, i, j, period)   # x_ji; x_ij = −x_ji (exact), so x_ij · n = −x_ji · n
            dot = -(d0 * normals[w, 0])
            if dim > 1:
                dot -= d1 * normals[w, 1]
            if dim > 2:
                dot -= d2 * normals[w, 2]
            if r2 < best:
                best = r2
                depth = offsets[w] - dot
                if half < np.inf:   # inside the cell of w only: not beyond its back, not beside it
                    inside = dot >= -half
                    for a in range(dim):
                        t = -(d0 if a == 0 else (d1 if a == 1 else d2)) - dot * normals[w, a]
                        if abs(t) > half:
                            inside = False
                    if not inside:
                        depth = 0.0
        out[i] = depth if depth > 0.0 else 0.0


def penetration_depths(indptr: NDArray[np.int64], indices: NDArray[np.int32], x: NDArray[np.float64],
                       n_fluid: int, normals: NDArray[np.float64], offsets: NDArray[np.float64],
                       spacing: float | None = None, period: NDArray[np.float64] | None = None
                       ) -> NDArray[np.float64]:
    """Depth ``(n_fluid,)`` (m) of each fluid particle behind the surface of its nearest wall
    particle (0 if in front of it, or without a wall neighbour). ``indptr, indices``: the
    neighbour table of all particles (fluid first); ``x (n, d)``; ``normals (n_w, d)`` and
    ``offsets (n_w,)`` of the wall particles ``n_fluid …``. With the wall's ``spacing`` (m), only
    a particle inside the cell of its nearest wall particle counts (module docstring); without
    it, every particle behind the plane of the nearest wall particle's surface. ``period (3,)``
    m: minimum-image offsets along the periodic axes (default none)."""
    out = np.empty(n_fluid)
    _depths(indptr, indices, x, n_fluid, normals, offsets, _half_cell(spacing), out, as_period(period))
    return out


def _half_cell(spacing: float | None) -> float:
    return np.inf if spacing is None else (0.5 + CELL_TOLERANCE) * float(spacing)


def penetration_depths_reference(indptr, indices, x, n_fluid, normals, offsets, spacing=None):
    """Numpy version of :func:`penetration_depths` (tests)."""
    half = _half_cell(spacing)
    out = np.zeros(n_fluid)
    for i in range(n_fluid):
        nb = indices[indptr[i]:indptr[i + 1]]
        nb = nb[nb >= n_fluid]
        if nb.size == 0:
            continue
        d = x[i] - x[nb]
        k = int(np.argmin(np.einsum("ij,ij->i", d, d)))
        w = nb[k] - n_fluid
        dot = d[k] @ normals[w]
        tangential = d[k] - dot * normals[w]
        if dot < -half or np.any(np.abs(tangential) > half):
            continue
        out[i] = max(offsets[w] - dot, 0.0)
    return out
