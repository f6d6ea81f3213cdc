r"""Linearly consistent nodal integration of the pressure force, with the free-surface boundary
term: the :class:`LinearConsistentPressure` effect (part of the recommended set, :data:`~mlsgalerkin.fluid.RECOMMENDED`).

**Why.** Direct nodal integration (DNI) of the internal force,
:math:`\mathbf f_i = \sum_k p_k\,\nabla N_i(\mathbf x_k)\,V_k`, integrates a *linear* pressure
field exactly only on a regular lattice away from any boundary. Measured in a 1 m × 0.3 m tank
of water at rest (``Δx = 0.02`` m, the particles at the exact hydrostatic densities), the first
evaluation leaves the top row with +5.7 % of ``g`` upwards, the row under it with −9.4 %, and the
corner particles with 16 % of ``g`` sideways; inside a disordered lattice the same residuals
make the hydrostatic state a saddle of the discrete energy, so particle rearrangements (the
diagonal slip of the lattice) release potential energy and grow (the kinetic energy tripled
every 0.25 s at Monaghan ``α = 0.02``, with or without a lid). The constant-only correction
(:mod:`~mlsgalerkin.fluid.consistent_integration`) is faded out near a free surface, where the
exact boundary term is not known, and does not correct the linear part.

**What.** For fluid node ``i``, the local linear fit of the pressure
:math:`\hat p_i(\mathbf x) = a_i + \mathbf g_i\cdot(\mathbf x - \mathbf x_i)` with the MLS value
:math:`a_i = \sum_j N_j(\mathbf x_i)\,p_j` and gradient :math:`\mathbf g_i = \sum_j p_j\nabla N_j(\mathbf x_i)`
is integrated exactly instead of by DNI, and the rest of the pressure field keeps DNI:

.. math::
    \mathbf f_i \mathrel{+}= -a_i\,\mathbf e_i - (\mathbf D_i + w_i\mathbf I)\,\mathbf g_i + \mathbf b_i,

with the DNI residuals :math:`\mathbf e_i = \sum_k\nabla N_i(\mathbf x_k)V_k`,
:math:`\mathbf D_i = \sum_k \nabla N_i(\mathbf x_k)\otimes(\mathbf x_k - \mathbf x_i)V_k`,
:math:`w_i = \sum_k N_i(\mathbf x_k)V_k` (DNI gives :math:`a_i\mathbf e_i + \mathbf D_i\mathbf g_i` for the
fit, the exact integral is :math:`-w_i\mathbf g_i + \oint_\Gamma \hat p_i N_i\,\mathbf n\,d\Gamma`), and
the free-surface boundary term taken on the outer faces of the surface particles,

.. math::
    \mathbf b_i = \sum_s p^h(\mathbf y_s)\,N_i(\mathbf y_s)\,\mathbf n_s\,A_s,\qquad
    \mathbf y_s = \mathbf x_s + \tfrac12\Delta x\,\mathbf n_s,\quad A_s = \Delta x^{d-1},

over the fluid particles ``s`` whose Shepard sum :math:`c_s = \sum_j W(\mathbf x_s - \mathbf x_j, h_j)V_j` (fluid and
wall neighbours) is below ``surface`` (0.85; 0.76 on a lattice's top row, 0.99 on the row
under it) and whose outward cone holds no neighbour (Marrone et al. 2010's scan,
:func:`~mlsgalerkin.fluid.free_surface.open_along_normal`: none within π/4 of the normal). Inside
a disordered fluid a particle next to a sparse patch has a Shepard sum as low as a surface's
(0.84 at ± 0.25 Δx of jitter); taken for a surface particle it carried the pressure of its depth
as a boundary load (5.7 ``g`` on an interior particle of the two-layer tank at rest, and a flow of
77 % of :math:`\sqrt{g'D}` within 1 s), with the outward normal
:math:`\mathbf n_s = -\sum_j V_j\nabla_s W_{sj}/|\cdot|` and
:math:`p^h(\mathbf y_s) = a_s + \mathbf g_s\cdot(\mathbf y_s - \mathbf x_s)` the surface particle's
pressure fit on its face; the shape functions on the face are those of the surface particle
continued to first order, :math:`N_j(\mathbf y_s) \approx N_j(\mathbf x_s) + \nabla N_j(\mathbf x_s)\cdot(\mathbf y_s -
\mathbf x_s)` (they keep the partition of unity and linear reproduction, and need no search). A
fluid at hydrostatic rest has :math:`p^h = 0` on the faces and feels no boundary term; a
pressure that does not vanish at the surface (the face of a dam at its release, a compression
wave reaching the surface) pushes it, as it should. Wall particles extend the fluid (a
fictitious layer), so walls need no boundary term. The correction is applied at fluid nodes
with :math:`c_i \ge` ``c_min`` (0.75) and shape functions of full order; splashes keep DNI.

**Only where the pressure is linear.** The correction is exact for the linear part of the
pressure, and its collocated term :math:`-w_i\mathbf g_i` is not the transpose of the
continuity equation's divergence, so, unlike DNI, it does not conserve the discrete energy.
Applied at every node of the dam break with impact it fed pressure bursts at the downstream
wall (P1 up to 13 ρgH at ``H/Δx = 20``, 5.6 without it). A node therefore keeps DNI where the
pressure over its support departs from the node's linear fit by more than
``linear_tol · |g_i| Δx`` (0.5): :math:`\max_j |p_j - a_i - \mathbf g_i\cdot(\mathbf x_j - \mathbf x_i)|`
over the entries of its row with :math:`N_j(\mathbf x_i) \ne 0` (a row may list a wall particle
outside its support, with ``p = 0`` when no fluid is in its reach; counted, it made a corner node of
a disordered start fall back to DNI). Water at rest (a linear pressure) is corrected everywhere;
an impact, a pressure
wave's crest or a flow whose pressure curves over a few spacings keeps DNI there.

**What the switch costs in a flow** (open; measured in the deep weakly stratified lock exchange
under a lid, ``gravity_current --set depth=0.12 --set rho_heavy=1100``, 20 rows, 2026-12-02). The
fronts' pressure departs from linear first (the heads' stagnation pressure, the lock's pressure
jump at the release); those nodes fall back to DNI, whose error on a disordered lattice scales
with the pressure itself (:math:`a_i\mathbf e_i`, about ``ρ g`` times the depth over the spacing
times the disorder); the noise it makes trips the neighbours. The corrected share falls from 1
at 0.07 s to 0.91 at 0.14 s and 0 at 0.8 s, the median departure grows from 3 Pa to 300 Pa,
and the light front runs at 0.81 of the heavy head. Corrected everywhere (``linear_tol``
unbounded) the departure
stays at 3–8 Pa, the fronts run alike (0.97; 0.98 and head +1.8 % at 40 rows, where the default
gives 0.68 and +18.5 %), but the geometric volume drifts (0.9 % and 2.7 %), the dam break with
impact gains energy and a free surface diverges. Measured and rejected: ``linear_tol = 2`` or 5
(the cascade comes later, at 0.5 s; the dam break's volume error 1.3 % and 3.1 %), the
constant part kept at the fallback nodes (P1 +42 %), the continuity equation made the transpose
of the corrected force, corrected everywhere (volume error 5.6 % in the dam break, 12 % in the
free-surface exchange),
the correction kept at every node away from a free surface (volume error 5.9 %). What would
remove it is a nodal integration that is linearly exact and conserves energy at once; a
prototype of one (``docs/theory/stabilisation.md`` §7) runs the fronts alike (0.99) but leaves
the pairing modes of nodal integration unresisted.

**A fixed hydrostatic reference in a closed tank** (``hydrostatic_reference=True``, the default
since 2026-12-05 and part of the recommended set; ``docs/theory/stabilisation.md`` §7, the eighth
candidate). Where a node falls back to DNI, DNI's error scales with the whole pressure, most of
which under a lid is hydrostatic. In an evaluation without a free-surface face and with gravity, a field of position
fixed at the first such evaluation,

.. math:: p_h(\mathbf x) = a + \rho_\text{ref}\,\mathbf g\cdot(\mathbf x - \bar{\mathbf x}),

(``ρ_ref`` and ``x̄`` the fluid's volume-weighted mean reference density and centroid; the slope
zero along periodic axes; ``a`` set so that the smallest residual ``p − p_h`` at that evaluation is
``reference_background`` (0.15) times the range of the pressure) is integrated exactly at the
nodes that fall back, and only ``p − p_h`` goes through DNI there:

.. math:: \mathbf f_i \mathrel{+}= -\sum_k V_k\bigl[\nabla N_i(\mathbf x_k)\,p_h(\mathbf x_k)
    + N_i(\mathbf x_k)\,\nabla p_h\bigr] \qquad (i \text{ not corrected}).

At the corrected nodes nothing changes (the fit of ``p − p_h`` plus the exact integral of ``p_h``
is the fit of ``p``), so a run in which no node falls back is the same bit for bit. The background
keeps the residual positive: with ``a`` at the mean, half the DNI nodes carry a tension of a few
pascals and pair (87 clumped pairs at 0.000 Δx in the deep exchange at 40 rows; none with a
background). Taken from the smallest residual, not the mean, it grows with the stratification: one
mean density leaves a residual of about ``±Δρ g D/2`` at the floor of a lock exchange, a quarter of
the range at ``Δρ/ρ0 = 1``, so the offset below the mean is 0.19 of the range at ``Δρ/ρ0 = 0.1``
and 0.4 at 1 (with a fixed 0.2 below the mean, the strong stratifications at ``D = 0.04`` m paired:
50–64 clumped pairs against 6–26).
Measured (one thread, ``gravity_current`` under its lid): the deep exchange at 40 rows
(D = 0.12 m, Δρ/ρ0 = 0.1) head −0.5 % and the fronts alike (light front 0.95 of the head; without
the reference: +20.5 %, 0.68), the weakly stratified D = 0.09 m, Δρ/ρ0 = 0.05 at 30 rows −2.4 %,
0.94 (without: +49.3 %, 0.33), each with at most two clumped pairs and the volume within 0.13 %;
the problem's 0.34 m tank at 20 rows, nine depths and density ratios, −9.9 to +1.0 % (without:
−9.6 to +9.2 %, the light front 0.37–0.83 of the head). A free surface keeps the plain
correction: there ``p_h`` does not vanish where the surface is not level.

**Measured** (1 m × 0.3 m tank at rest, ``Δx = 0.02`` m, ``α = 0.02``, ``δ = 0.1``, local
shifting, 2 s): largest speed 0.03 % of :math:`\sqrt{gH}` (DNI: 3.7 %, growing), pressure RMS
deviation 0.13–0.18 % of :math:`\rho gH` (DNI: 0.67 %, growing), with or without tension
released. The dam break with impact at ``H/Δx = 20`` and 40: see
``verification/results/quiet_state/investigation.md`` §7, with the ablations.

**What it costs and breaks.** The Shepard sums and their gradients come with the shape-function
table (the solver asks for them when an effect reads ``kernel_sum``: three more sums in the
moment-matrix pass); then two compiled passes per force evaluation: a gather over the fluid rows
of the table (the pressure fits) and a scatter over all its rows (the corrected force and the
boundary term); numba kernels with a numpy reference (:func:`linear_consistency_force_reference`).
About 1.5 times the internal force's scatter (``benchmarks/results/fluid_run_impact.md`` has the
whole-run cost). Periodic axes are handled by the minimum image of every offset. Like the
constant correction it gives up the exact momentum balance :math:`\sum_i\mathbf f_i = 0` by the
size of the integration residual times the pressure.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

from mlsgalerkin.fluid.effect import Effect, EffectContext
from mlsgalerkin.fluid.free_surface import open_along_normal, open_along_normal_reference
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.kernels import Kernel
from mlsgalerkin.pairs import image_component
from mlsgalerkin.periodic import minimum_image

__all__ = ["LinearConsistentPressure", "hydrostatic_reference", "hydrostatic_reference_force", "hydrostatic_reference_force_reference",
           "linear_consistency_force", "linear_consistency_force_reference", "surface_faces", "surface_faces_reference"]

FloatArray = NDArray[np.float64]


@numba.njit(parallel=True, cache=True)
def _corrected_gather(col_ptr, col_pairs, col_rows, values, grads, x, V, fit, ok, face_of, delta, load, period,
                       n_fluid):
    """``Δf_j`` of the corrected fluid nodes ``j`` (``ok[j]``), each summed over its column of the
    table (:meth:`~mlsgalerkin.approximation.table.ShapeTable.node_columns`) in ascending row ``k``:

    ``Δf_j −= V_k [∇N_j(x_k) (a_j + g_j·(x_k − x_j)) + N_j(x_k) g_j]`` (the DNI of the fit taken out
    and its exact volume integral put in; ``fit[j] = (a_j, g_j)``) and, on the row of a surface
    particle with face ``f = face_of[k] ≥ 0``, ``Δf_j += (N_j(x_k) + ∇N_j(x_k)·δ_f) load_f`` (the
    boundary term). ``x_k − x_j`` is the minimum image along the periodic axes."""
    dim = grads.shape[1]
    out = np.zeros((n_fluid, dim))
    for j in prange(n_fluid):
        if not ok[j]:
            continue
        for t in range(col_ptr[j], col_ptr[j + 1]):
            q = col_pairs[t]
            k = col_rows[t]
            vk = V[k]
            f = face_of[k] if k < n_fluid else -1
            fit_value = fit[j, 0]
            for b in range(dim):
                fit_value += fit[j, 1 + b] * image_component(x[k, b] - x[j, b], period[b])
            nv = values[q]
            for a in range(dim):
                out[j, a] -= vk * (grads[q, a] * fit_value + nv * fit[j, 1 + a])
            if f >= 0:
                for b in range(dim):
                    nv += grads[q, b] * delta[f, b]
                for a in range(dim):
                    out[j, a] += nv * load[f, a]
    return out


@numba.njit(parallel=True, cache=True)
def _fit(indptr, indices, values, grads, p, x, period, n_fluid, fit, departure):
    """The pressure fits ``fit[i] = (a_i, g_i) = (Σ_j N_j(x_i) p_j, Σ_j ∇N_j(x_i) p_j)`` of the
    fluid rows ``i < n_fluid`` of the table (a gather), and how far the pressure departs from
    its fit over the row, ``departure[i] = max_j |p_j − a_i − g_i·(x_j − x_i)|`` over the
    entries with ``N_j(x_i) ≠ 0`` (Pa; minimum image along periodic axes). A row may list
    neighbours outside their support (``N_j = 0``): a wall particle with no fluid in its reach
    has ``p = 0``, and counted it would mark a corner node of a disordered start as nonlinear."""
    dim = grads.shape[1]
    for i in prange(n_fluid):
        a0 = g0 = g1 = g2 = 0.0
        for q in range(indptr[i], indptr[i + 1]):
            pj = p[indices[q]]
            a0 += values[q] * pj
            g0 += grads[q, 0] * pj
            if dim > 1:
                g1 += grads[q, 1] * pj
            if dim > 2:
                g2 += grads[q, 2] * pj
        fit[i, 0] = a0
        fit[i, 1] = g0
        if dim > 1:
            fit[i, 2] = g1
        if dim > 2:
            fit[i, 3] = g2
        worst = 0.0
        for q in range(indptr[i], indptr[i + 1]):
            if values[q] == 0.0:     # a neighbour outside node j's support: not part of the fit
                continue
            j = indices[q]
            r = p[j] - a0 - g0 * image_component(x[j, 0] - x[i, 0], period[0])
            if dim > 1:
                r -= g1 * image_component(x[j, 1] - x[i, 1], period[1])
            if dim > 2:
                r -= g2 * image_component(x[j, 2] - x[i, 2], period[2])
            worst = max(worst, abs(r))
        departure[i] = worst


def surface_faces_reference(s: FluidState, kernel: Kernel, surface: float) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
    """Numpy version of :func:`surface_faces` (tests)."""
    nf, x, d = s.n_fluid, s.x, s.x.shape[1]
    nb = s.neighbors
    ip = nb.indptr[: nf + 1]
    idx = nb.indices[: ip[-1]].astype(np.int64)
    rows = np.repeat(np.arange(nf), np.diff(ip))
    xji = minimum_image(x[idx] - x[rows], s.period)
    r = np.sqrt(np.einsum("pd,pd->p", xji, xji))
    hij = s.h[idx]
    V = s.volume          # the volumes M/ρ of the evaluation the table was built for
    c = np.bincount(rows, kernel.value(r, hij, d) * V[idx], minlength=nf)
    safe = np.where(r > 0, r, 1.0)
    dw = np.where(r > 0, kernel.derivative(r, hij, d) / safe, 0.0) * V[idx]     # V_j W'(r)/r
    # Σ_j V_j ∇_i W_ij = −Σ_j V_j W'/r x_ji; the outward normal is its negative
    normal = np.stack([np.bincount(rows, dw * xji[:, a], minlength=nf) for a in range(d)], axis=1)
    length = np.sqrt(np.einsum("id,id->i", normal, normal))
    surf = np.flatnonzero((c < surface) & (length > 0))
    n_s = normal[surf] / length[surf, None]
    keep = open_along_normal_reference(x, nb, surf, n_s, period=s.period)
    return c, n_s[keep], surf[keep]


def linear_consistency_force_reference(s: FluidState, kernel: Kernel, *, surface: float = 0.85, c_min: float = 0.75,
                                       linear_tol: float = 0.5) -> tuple[FloatArray, NDArray[np.bool_], int]:
    """Numpy version of :func:`linear_consistency_force` (tests), with sparse matrices."""
    t = s.table
    nf, x, d = s.n_fluid, s.x, s.x.shape[1]
    N = t.value_matrix()                 # (points, nodes): N_j(x_k)
    G = t.gradient_matrices()
    V = np.ascontiguousarray(s.volume)
    p = s.p
    e = np.stack([G[b].T @ V for b in range(d)], axis=1)
    w = N.T @ V
    a = N @ p
    g = np.stack([G[b] @ p for b in range(d)], axis=1)
    # D_j = Σ_k ∇N_j(x_k) ⊗ (x_k − x_j) V_k over the table's entries (k, j), minimum image
    k_of = np.repeat(np.arange(t.n_points), np.diff(t.indptr))
    j_of = t.indices.astype(np.int64)
    offset = minimum_image(x[k_of] - x[j_of], s.period) * V[k_of, None]
    D = np.stack([np.stack([np.bincount(j_of, t.gradients[:, al] * offset[:, be], minlength=x.shape[0])
                            for be in range(d)], axis=1) for al in range(d)], axis=1)
    D += w[:, None, None] * np.eye(d)
    df = -a[:, None] * e - np.einsum("iab,ib->ia", D, g)
    c, n_s, surf = surface_faces_reference(s, kernel, surface)
    if surf.size:
        delta = 0.5 * s.spacing * n_s                                  # y_s − x_s
        Nf = N[surf] + sum(G[b][surf].multiply(delta[:, b:b + 1]) for b in range(d))   # N_j(y_s), first order
        ph = a[surf] + np.einsum("sd,sd->s", g[surf], delta)            # p^h(y_s) of the linear fit
        df += Nf.T @ ((ph * s.spacing ** (d - 1))[:, None] * n_s)
    # departure of the pressure from each fluid row's fit, over the row's entries (minimum image)
    rows = k_of[: t.indptr[nf]]
    cols = j_of[: t.indptr[nf]]
    off = minimum_image(x[cols] - x[rows], s.period)
    r = np.abs(p[cols] - a[rows] - np.einsum("pd,pd->p", g[rows], off))
    r[t.values[: t.indptr[nf]] == 0.0] = 0.0        # neighbours outside their support
    departure = np.zeros(nf)
    np.maximum.at(departure, rows, r)
    slope = np.sqrt(np.einsum("id,id->i", g[:nf], g[:nf]))
    ok = (c >= c_min) & (t.order[:nf] >= s.approximation_order) & (departure <= linear_tol * slope * s.spacing)
    out = np.where(ok[:, None], df[:nf], 0.0)
    return out, ok, int(surf.size)


def hydrostatic_reference(s: FluidState, background: float) -> dict[str, Any]:
    """The fixed hydrostatic reference of the module docstring from the current state: ``rho_ref``
    (kg/m^3) and ``centroid`` ``(d,)`` (m), the fluid's volume-weighted mean reference density and
    position; ``slope`` ``(d,)`` (Pa/m), ``ρ_ref g`` with zero along periodic axes; ``a`` (Pa), the
    smallest ``p − slope·(x − x̄)`` over the fluid less ``background`` times the range of the fluid's
    pressure, so that ``min(p − p_h) = background · ptp(p)``. Lists and floats, so that a checkpoint
    keeps them to the bit."""
    if s.gravity is None:
        raise ValueError("a hydrostatic reference needs gravity (list Gravity())")
    nf, d = s.n_fluid, s.x.shape[1]
    V = np.asarray(s.volume[:nf], dtype=float)
    x = s.x[:nf]
    rho_ref = float(np.average(s.rho0[:nf], weights=V))
    centroid = np.average(x, axis=0, weights=V)
    slope = rho_ref * np.asarray(s.gravity, dtype=float)[:d]
    slope[np.asarray(s.period[:d]) > 0.0] = 0.0
    p = np.asarray(s.p[:nf], dtype=float)
    a = float(np.min(p - (x - centroid) @ slope)) - background * float(np.ptp(p))
    return {"rho_ref": rho_ref, "centroid": centroid.tolist(), "slope": slope.tolist(), "a": a}


def _reference_fit(s: FluidState, reference: dict[str, Any]) -> FloatArray:
    """``(n_fluid, d + 1)``: the reference's value at each fluid node and its (constant) slope."""
    nf, d = s.n_fluid, s.x.shape[1]
    slope = np.asarray(reference["slope"], dtype=float)
    fit = np.empty((nf, d + 1))
    fit[:, 0] = reference["a"] + (s.x[:nf] - np.asarray(reference["centroid"], dtype=float)) @ slope
    fit[:, 1:] = slope
    return fit


def hydrostatic_reference_force(s: FluidState, reference: dict[str, Any],
                                corrected: NDArray[np.bool_]) -> FloatArray:
    """``Δf (n_fluid, d)`` (N per unit depth in 2D) of the fixed hydrostatic reference (module
    docstring) at the fluid nodes that are not ``corrected``: the DNI of ``p_h`` taken out and its
    exact volume integral put in, ``−Σ_k V_k [∇N_i(x_k) p_h(x_k) + N_i(x_k) ∇p_h]``; zero at the
    corrected nodes. One compiled gather over the table's node columns."""
    t = s.table
    nf, d = s.n_fluid, s.x.shape[1]
    cols = t.node_columns()
    V = np.ascontiguousarray(s.volume, dtype=float)
    none = np.zeros((0, d))
    return _corrected_gather(cols.indptr, cols.pairs, cols.rows, t.values, t.gradients, s.x, V,
                             _reference_fit(s, reference), ~np.asarray(corrected, dtype=bool),
                             np.full(nf, -1, dtype=np.int64), none, none, s.period, nf)


def hydrostatic_reference_force_reference(s: FluidState, reference: dict[str, Any],
                                          corrected: NDArray[np.bool_]) -> FloatArray:
    """Numpy version of :func:`hydrostatic_reference_force` (tests), with sparse matrices."""
    t = s.table
    nf, d = s.n_fluid, s.x.shape[1]
    N = t.value_matrix()
    G = t.gradient_matrices()
    V = np.asarray(s.volume, dtype=float)
    slope = np.asarray(reference["slope"], dtype=float)
    ph = reference["a"] + (s.x - np.asarray(reference["centroid"], dtype=float)) @ slope
    df = -np.stack([G[b].T @ (V * ph) for b in range(d)], axis=1) - (N.T @ V)[:, None] * slope[None, :]
    return np.where(np.asarray(corrected, dtype=bool)[:, None], 0.0, df[:nf])


def _corrected_nodes(s: FluidState, c: FloatArray, fit: FloatArray, departure: FloatArray, c_min: float,
                     linear_tol: float) -> NDArray[np.bool_]:
    """The fluid nodes that get the correction: Shepard sum at least ``c_min``, shape functions of
    full order, and a pressure within ``linear_tol · |g_i| Δx`` of its linear fit over the row."""
    nf = s.n_fluid
    slope = np.sqrt(np.einsum("id,id->i", fit[:, 1:], fit[:, 1:]))
    return ((c >= c_min) & (s.table.order[:nf] >= s.approximation_order)
            & (departure <= linear_tol * slope * s.spacing))


def _faces(c: FloatArray, normal: FloatArray, surface: float) -> tuple[FloatArray, NDArray[np.int64]]:
    """Unit outward normals ``(m, d)`` and indices ``(m,)`` of the particles with ``c < surface``."""
    length = np.sqrt(np.einsum("id,id->i", normal, normal))
    surf = np.flatnonzero((c < surface) & (length > 0))
    return normal[surf] / length[surf, None], surf


def surface_faces(s: FluidState, surface: float) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
    """Shepard sums ``c (n_fluid,)`` of the fluid particles over all their neighbours, and the
    outward unit normals ``n (m, d)`` of the ``m`` fluid particles with ``c < surface`` and
    their indices ``(m,)`` (module docstring): the table's ``kernel_sum`` and the opposite of
    its gradient, which the solver fills when an effect reads ``kernel_sum``."""
    t = s.table
    if t.kernel_sum is None:
        raise ValueError("the shape-function table carries no Shepard sums: build it with kernel_sum_volumes "
                         "(the fluid solver does when an effect reads 'kernel_sum')")
    nf = s.n_fluid
    c = t.kernel_sum[:nf]
    n_s, surf = _faces(c, -t.kernel_sum_gradient[:nf], surface)
    keep = open_along_normal(s.x, s.neighbors, surf, n_s, period=s.period)
    return c, n_s[keep], surf[keep]


def linear_consistency_force(s: FluidState, *, surface: float = 0.85, c_min: float = 0.75,
                             linear_tol: float = 0.5) -> tuple[FloatArray, NDArray[np.bool_], int]:
    """The correction ``Δf (n_fluid, d)`` (N per unit depth in 2D) of the module docstring at the
    current state (table with its Shepard sums, volumes, pressures), the mask ``(n_fluid,)`` of
    corrected fluid nodes and the number of surface faces. Two compiled passes: a gather over the
    table's fluid rows (:func:`_fit`) and a gather over the table's node columns (:func:`_corrected_gather`);
    :func:`linear_consistency_force_reference` is the numpy version."""
    t = s.table
    nf, d = s.n_fluid, s.x.shape[1]
    c, n_s, surf = surface_faces(s, surface)
    fit, departure = np.empty((nf, d + 1)), np.empty(nf)
    _fit(t.indptr, t.indices, t.values, t.gradients, np.ascontiguousarray(s.p, dtype=float), s.x, s.period, nf, fit,
         departure)
    ok = _corrected_nodes(s, c, fit, departure, c_min, linear_tol)
    face_of = np.full(nf, -1, dtype=np.int64)
    face_of[surf] = np.arange(surf.size)
    delta = np.ascontiguousarray(0.5 * s.spacing * n_s)
    ph = fit[surf, 0] + np.einsum("sd,sd->s", fit[surf, 1:], delta)
    load = np.ascontiguousarray((ph * s.spacing ** (d - 1))[:, None] * n_s)
    cols = t.node_columns()
    df = _corrected_gather(cols.indptr, cols.pairs, cols.rows, t.values, t.gradients, s.x,
                            np.ascontiguousarray(s.volume, dtype=float), fit, ok, face_of, delta, load,
                            s.period, nf)
    return df, ok, int(surf.size)


class LinearConsistentPressure(Effect):
    """Linearly consistent integration of the pressure force with the free-surface boundary term
    (module docstring): ``f_i += −a_i e_i − (D_i + w_i I) g_i + b_i`` at the fluid nodes with a
    Shepard sum of at least ``c_min``; ``surface`` is the Shepard sum below which a particle is a
    surface candidate (confirmed by the normal-cone scan). Part of the recommended set.
    ``hydrostatic_reference`` (on by default): in a closed tank, the fixed hydrostatic field,
    whose smallest residual is ``reference_background`` times the pressure's range, integrated
    exactly at the nodes that fall back (module docstring); fixed at the first evaluation without
    a free-surface face, kept in checkpoints and reported in the summary."""

    name = "linear_consistent_pressure"
    stabilising = True
    stages = ("force",)
    reads = ("shape_functions", "volume", "kernel_sum")

    def __init__(self, *, surface: float = 0.85, c_min: float = 0.75, linear_tol: float = 0.5,
                 hydrostatic_reference: bool = True, reference_background: float = 0.15) -> None:
        self.surface, self.c_min, self.linear_tol = float(surface), float(c_min), float(linear_tol)
        self.hydrostatic_reference = hydrostatic_reference
        self.reference_background = reference_background
        self.reference: dict[str, Any] | None = None   # fixed at the first closed evaluation
        self.reference_evaluations = 0
        self.corrected_share = float("nan")
        self.faces = 0

    def __repr__(self) -> str:
        reference = (f", hydrostatic_reference=True, reference_background={self.reference_background:g}"
                     if self.hydrostatic_reference else "")
        return (f"LinearConsistentPressure(surface={self.surface:g}, c_min={self.c_min:g}, "
                f"linear_tol={self.linear_tol:g}{reference})")

    def check(self, ctx: EffectContext) -> list[str]:
        out = []
        if not (0.0 < self.c_min <= self.surface < 1.0):
            out.append(f"LinearConsistentPressure: need 0 < c_min <= surface < 1 (Shepard sums), got c_min = "
                       f"{self.c_min:g}, surface = {self.surface:g}; the defaults are 0.75 and 0.85")
        if not self.linear_tol > 0.0:
            out.append(f"LinearConsistentPressure: linear_tol must be > 0 (a multiple of |grad p| dx), got "
                       f"{self.linear_tol:g}; the default is 0.5")
        if not isinstance(self.hydrostatic_reference, bool):
            out.append(f"LinearConsistentPressure: hydrostatic_reference must be True or False, got "
                       f"{self.hydrostatic_reference!r}")
        if not (isinstance(self.reference_background, (int, float)) and 0.0 <= self.reference_background < math.inf):
            out.append(f"LinearConsistentPressure: reference_background must be a finite number >= 0 (a share of "
                       f"the pressure's range), got {self.reference_background!r}; the default is 0.15")
        if ctx.approximation.order < 1:
            out.append("LinearConsistentPressure needs a linear (or higher) basis: the pressure fit is linear")
        return out

    def force(self, s: FluidState) -> None:
        df, ok, faces = linear_consistency_force(s, surface=self.surface, c_min=self.c_min,
                                                 linear_tol=self.linear_tol)
        if self.hydrostatic_reference and faces == 0 and s.gravity is not None:   # a closed tank
            if self.reference is None:
                self.reference = hydrostatic_reference(s, float(self.reference_background))
            if not ok.all():
                df += hydrostatic_reference_force(s, self.reference, ok)
                self.reference_evaluations += 1
        s.force[s.fluid] += df
        self.corrected_share = float(np.mean(ok)) if ok.size else float("nan")
        self.faces = faces

    def summary(self) -> dict[str, Any]:
        return {"corrected_share_at_end": self.corrected_share, "surface_faces_at_end": self.faces,
                "surface": self.surface, "c_min": self.c_min, "linear_tol": self.linear_tol,
                "hydrostatic_reference": {"on": self.hydrostatic_reference, "background": self.reference_background,
                                          "reference": self.reference,
                                          "evaluations_applied": self.reference_evaluations}}

    def state_dict(self) -> dict[str, Any]:
        return {"reference": self.reference, "reference_evaluations": self.reference_evaluations}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.reference = d.get("reference")
        self.reference_evaluations = int(d.get("reference_evaluations", 0))
