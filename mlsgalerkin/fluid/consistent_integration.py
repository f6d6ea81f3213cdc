r"""Variationally consistent nodal integration: the :class:`ConsistentIntegration` effect and its
kernel (the linear correction of Chen, Hillman & Rüter 2013).

**Why.** The Galerkin weak form needs the *integration constraint*: for a node ``i`` whose
support lies inside the fluid, :math:`\int_\Omega \nabla N_i\,d\Omega = \mathbf 0`, so a uniform
pressure exerts no force on it. Direct nodal integration meets it only on a regular lattice
(by symmetry). On a disordered one its residual

.. math:: \mathbf e_i = \sum_k \nabla N_i(\mathbf x_k)\,V_k

is not zero, and a pressure ``p₀`` pushes node ``i`` with ``p₀ e_i``. The residual grows with
the disorder, so under pressure the particle lattice is unstable: measured in a closed box
without gravity (20 × 40 particles, ``Δx = 3`` mm, Monaghan α = 0.1), random velocities of
0.1 mm/s decay at ``p₀ = 0`` but grow to 4 mm/s within 0.6 s at ``p₀ = 600`` Pa (the pressure
at the bottom of a 6 cm tank). In a two-layer tank at rest under a lid this is the diagonal
shearing of the lattice, with a pressure checkerboard, that grew by e every 0.2 s.

**What.** The test-function gradients are corrected so that the constraint holds exactly
(Chen, Hillman & Rüter 2013's linear variationally consistent integration, VCI):

.. math::
    \widetilde{\nabla N}_i(\mathbf x_k) = \nabla N_i(\mathbf x_k) + \boldsymbol\xi_i\,N_i(\mathbf x_k),
    \qquad \boldsymbol\xi_i = -\chi_i\,\frac{\mathbf e_i}{w_i},\qquad w_i = \sum_k N_i(\mathbf x_k)\,V_k,

so :math:`\sum_k \widetilde{\nabla N}_i(\mathbf x_k)V_k = (1 - \chi_i)\,\mathbf e_i`. The internal
force :math:`\mathbf f_i = -\sum_k\boldsymbol\sigma_k\widetilde{\nabla N}_i(\mathbf x_k)V_k` becomes

.. math:: \mathbf f_i = \mathbf f_i^{nodal} + \chi_i\,\bar{\boldsymbol\sigma}_i\,\mathbf e_i,
          \qquad \bar{\boldsymbol\sigma}_i = \frac{\sum_k N_i(\mathbf x_k)\,\boldsymbol\sigma_k V_k}{w_i},

(for the pressure alone, ``−p̄_i e_i``: the force of a uniform pressure is removed). Only the
test functions change (Petrov–Galerkin); the velocity gradient and the continuity equation
keep the MLS gradients, which reproduce linear fields exactly.

**Where.** The exact boundary term of a node whose support reaches a free surface is not
known (the surface is not traced), so the correction is faded out there. With the Shepard sum
:math:`c_k = \sum_j W(|\mathbf x_k - \mathbf x_j|, h_k)\,V_j` over fluid and wall neighbours
(1 inside a lattice, 0.76 on its top row, 0.99 on the row under it; in a disordered interior,
positions jittered by ±0.15 Δx, between 0.90 and 1.10) and ``c_i⁻`` its smallest value over
the points whose row holds node ``i``,

.. math:: \chi_i = \mathrm{clip}\Big(\frac{c_i^- - c_{none}}{c_{full} - c_{none}},\ 0,\ 1\Big),
          \qquad c_{none} = 0.80,\ c_{full} = 0.88 .

Wall particles extend the fluid, so a node near a wall keeps the full correction; the nodes
within a support of a free surface or a splash keep direct nodal integration.

**What it costs and breaks.** One pass over the pairs for ``c`` and one scatter over the shape
table (about the internal force's cost). :math:`\sum_i\mathbf f_i` is no longer exactly zero
(the correction has no partner), and the exact exchange between the work of the internal
forces and the stored energy (``docs/theory/galerkin_fluid.md`` §3) holds only for nodes with
``χ = 0``. Both errors are of the size of the integration residual times the pressure.

A numba kernel with a numpy reference (:func:`shepard_sum_reference`,
:func:`consistency_force_reference`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

from mlsgalerkin.assembly import integration_terms, integration_terms_reference
from mlsgalerkin.fluid.effect import Effect, EffectContext
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.kernels import Kernel, get_kernel, kernel_f_df
from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period, minimum_image

if TYPE_CHECKING:  # pragma: no cover
    from mlsgalerkin.approximation.table import ShapeTable

__all__ = ["ConsistentIntegration", "shepard_sum", "shepard_sum_reference", "consistency_force",
           "consistency_force_reference", "fade"]

FloatArray = NDArray[np.float64]


@numba.njit(parallel=True, cache=True)
def _shepard(x, h, volume, indptr, indices, kid, support, norm_d, out, period):
    n, dim = x.shape[0], x.shape[1]
    for k in prange(indptr.shape[0] - 1):
        hk = h[k]
        acc = 0.0
        for p in range(indptr[k], indptr[k + 1]):
            j = indices[p]
            _, _, _, r2 = pair_offset(x, k, j, period)
            f, _ = kernel_f_df(kid, np.sqrt(r2) / hk, support, dim)
            acc += f * volume[j]
        out[k] = acc * norm_d / hk**dim


def shepard_sum(x: FloatArray, h: FloatArray, volume: FloatArray, table: "ShapeTable", kernel: Kernel,
                period: FloatArray | None = None) -> FloatArray:
    """``c_k = Σ_j W(|x_k − x_j|, h_k) V_j`` over the row ``k`` of ``table`` (the point's own
    term included), ``(n_points,)``, dimensionless; ``period (3,)`` m: minimum-image distances
    along the periodic axes (default none)."""
    dim = x.shape[1]
    out = np.empty(table.n_points)
    _shepard(x, h, volume, table.indptr, table.indices, kernel.kernel_id, kernel.support, kernel.normalisation(dim),
             out, as_period(period))
    return out


def shepard_sum_reference(x: FloatArray, h: FloatArray, volume: FloatArray, table: "ShapeTable",
                          kernel: Kernel, period: FloatArray | None = None) -> FloatArray:
    """Numpy version of :func:`shepard_sum` (tests)."""
    rows = np.repeat(np.arange(table.n_points), np.diff(table.indptr))
    r = np.linalg.norm(minimum_image(x[table.indices] - x[rows], as_period(period)), axis=1)
    W = kernel.value(r, h[rows], x.shape[1])
    return np.bincount(rows, W * volume[table.indices], minlength=table.n_points)


def fade(lowest: FloatArray, none: float, full: float) -> FloatArray:
    """``χ = clip((lowest − none)/(full − none), 0, 1)``."""
    return np.clip((lowest - none) / (full - none), 0.0, 1.0)


@numba.njit(parallel=True, cache=True)
def _correction(residual, volume, stress_volume, lowest, none, full, df, chi):
    n, dim = residual.shape
    for i in prange(n):
        x = (lowest[i] - none) / (full - none)
        x = min(max(x, 0.0), 1.0)
        chi[i] = x
        w = volume[i]
        scale = x / w if w != 0.0 and x > 0.0 else 0.0
        for a in range(dim):
            acc = 0.0
            for b in range(dim):
                acc += stress_volume[i, a, b] * residual[i, b]
            df[i, a] = acc * scale


def consistency_force(table: "ShapeTable", volume: FloatArray, stress_volume: FloatArray, shepard: FloatArray,
                      none: float = 0.80, full: float = 0.88) -> tuple[FloatArray, FloatArray]:
    """The correction ``Δf_i = χ_i σ̄_i e_i`` ``(n_nodes, d)`` (N per unit depth in 2D) and ``χ``
    ``(n_nodes,)`` from the volumes ``V (n_points,)``, ``σ V (n_points, d, d)`` and the Shepard
    sums ``c (n_points,)`` (module docstring)."""
    t = integration_terms(table, volume, stress_volume, shepard)
    df = np.empty_like(t.residual)
    chi = np.empty(table.n_nodes)
    _correction(t.residual, t.volume, t.stress_volume, t.lowest, float(none), float(full), df, chi)
    return df, chi


def consistency_force_reference(table: "ShapeTable", volume: FloatArray, stress_volume: FloatArray,
                                shepard: FloatArray, none: float = 0.80,
                                full: float = 0.88) -> tuple[FloatArray, FloatArray]:
    """Numpy version of :func:`consistency_force` (tests)."""
    t = integration_terms_reference(table, volume, stress_volume, shepard)
    chi = fade(t.lowest, none, full)
    dF = np.einsum("iab,ib->ia", t.stress_volume, t.residual) / t.volume[:, None]
    return dF * chi[:, None], chi


class ConsistentIntegration(Effect):
    """Variationally consistent nodal integration of the internal force (module docstring):
    ``f_i += χ_i σ̄_i e_i`` on the fluid nodes, so a uniform pressure exerts no force on a node
    whose support lies inside the fluid and walls.

    ``none`` and ``full``: the Shepard sums between which the correction fades in (defaults
    0.80 and 0.88). ``summary()`` reports the share of fluid nodes with the full correction at
    the last evaluation.
    """

    name = "consistent_integration"
    stabilising = True
    stages = ("force",)
    reads = ("shape_functions", "volume")

    def __init__(self, *, none: float = 0.80, full: float = 0.88) -> None:
        self.none, self.full = float(none), float(full)
        self._kernel: Kernel | None = None
        self._chi: FloatArray | None = None

    def __repr__(self) -> str:
        return f"ConsistentIntegration(none={self.none:g}, full={self.full:g})"

    def check(self, ctx: EffectContext) -> list[str]:
        if not (0.0 < self.none < self.full <= 1.0):
            return [f"ConsistentIntegration: need 0 < none < full <= 1 (Shepard sums), got none = {self.none:g}, "
                    f"full = {self.full:g}; the defaults are 0.80 and 0.88"]
        return []

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        self._kernel = get_kernel(ctx.approximation.kernel)

    def force(self, s: FluidState) -> None:
        volume = np.ascontiguousarray(s.volume)
        shepard = shepard_sum(s.x, s.h, volume, s.table, self._kernel, s.period)
        sv = np.ascontiguousarray(s.stress * volume[:, None, None])
        df, chi = consistency_force(s.table, volume, sv, shepard, self.none, self.full)
        f = s.fluid
        s.force[f] += df[f]
        self._chi = chi[f]

    def summary(self) -> dict[str, Any]:
        chi = self._chi
        share = float(np.mean(chi >= 1.0)) if chi is not None and chi.size else float("nan")
        return {"full_correction_share_at_end": share, "none": self.none, "full": self.full}
