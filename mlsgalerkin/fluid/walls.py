r"""Wall particles: the state of the fictitious fluid beyond a wall (the :class:`Walls` effect and
its kernel).

Wall particles are nodes of the MLS approximation *and* integration points of the nodal
Galerkin sums, so the weak form integrates over the fluid and a fictitious layer beyond the
wall. Their state is extrapolated from the fluid particles ``f`` in reach every step, with the
kernel weights ``W_wf = W(|x_w − x_f|, h_f)`` (Adami, Hu & Adams 2012):

.. math::

    p_w = \frac{\sum_f p_f W_{wf} + (\mathbf g - \mathbf a_w)\cdot\sum_f \rho_f
          (\mathbf x_w - \mathbf x_f) W_{wf}}{\sum_f W_{wf}},\qquad
    \rho_w = \frac{\sum_f \rho_f W_{wf}}{\sum_f W_{wf}},\qquad
    \tilde{\mathbf v}_w = \frac{\sum_f \mathbf v_f W_{wf}}{\sum_f W_{wf}},

so a fluid at hydrostatic rest sees the hydrostatic pressure continued into the wall, and the
pressure force ``−Σ_k σ_k ∇N_i(x_k) V_k`` on a fluid node near the wall is balanced by its
weight. The wall-particle velocity that enters the velocity approximation is

- ``"no_slip"``: the continuation of the fluid velocity through ``v_wall`` on the wall surface,
  per wall particle: ``v_w = v_wall − d_w B n + c d_w²``, with ``d_w`` the particle's depth behind
  the surface (``Δx/2`` plus the offset along ``n`` of the wall particle of its column nearest
  the fluid) and ``B, c`` the weighted least-squares fit
  ``v_f ≈ v_wall + B(x_f − x_s) + c((x_f − x_s)·n)²`` over the fluid in reach of that column's
  top particle, ``x_s = x_w + d_w n`` the particle's foot on the surface
  (:func:`no_slip_wall_velocity`). A shear profile linear or quadratic across the wall (Couette,
  Poiseuille) is continued exactly into every layer. In a corner (a wall particle in reach facing
  more than 25° away) and where the fit would continue the fluid beyond ``2 d_w/Δx`` times its
  largest speed relative to the wall, the Shepard mirror ``2 v_wall − ṽ_w`` below instead (the
  lock-exchange tank diverged at a corner without it). (Adami, Hu & Adams 2012's ``2 v_wall − ṽ_w`` with the Shepard mean
  ``ṽ_w`` gave all layers about the velocity of the fluid 1.5 Δx from the wall and the deepest
  layer, with no fluid in reach, ``v_wall``: in plane Poiseuille flow, H/Δx = 20, the layers at
  0.5, 1.5, 2.5 Δx got −0.109, −0.102, 0 where the parabola continued has −0.103, −0.323,
  −0.563 of ``u_max`` (the fit: −0.102, −0.321, −0.561), and the rows of the channel alternated
  by 19 % of ``u_max``.) The fit gives the tangential component only; the normal component is
  the free-slip mirror's, ``v_wall·n − (ṽ_w − v_wall)·n`` (:func:`with_normal_component_of`): the
  fit's even (quadratic) part continues a fluid row's normal motion into the wall in the same
  sense, up to ``2 d_w/Δx`` times larger, so the wall does not resist a row moving onto it, and
  the normal noise of the row next to a lid grew: in the lock exchange under a lid
  (``D = 0.04`` m, ``Δρ/ρ0 = 0.1``, ``Δx = 4`` mm, α = 0.02, linear consistency) the spread of
  the top row's pressure grew from 45 Pa to 4000 Pa within 0.9 s (``ρgD = 431`` Pa) and the row
  clumped at 1.2 s; with the mirrored normal it stays at 40–240 Pa to 1 s, as with free slip.
  Needs the wall normals;
- ``"free_slip"``: ``v_w = ṽ_w − 2 ((ṽ_w − v_wall)·n) n`` (normal component mirrored,
  tangential component continued; needs the wall normals ``n``);
- ``"fixed"``: ``v_w = v_wall``.

A wall particle with no fluid in reach gets ``p = 0``, its reference density and ``v_wall``.
Wall particles keep the volume ``Δx^d``; their mass ``ρ_w Δx^d`` follows the extrapolated
density. A wall with a prescribed motion (:class:`~mlsgalerkin.fluid.bodies.WallBody`
``motion=``) supplies ``v_wall`` and ``a_w`` per wall particle at each evaluation's time; a
fixed wall has ``a_w = 0`` and the ``v_wall`` of its body (a moving belt if non-zero).
"""

from __future__ import annotations

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

from mlsgalerkin.fluid.bodies import WallBody
from mlsgalerkin.fluid.effect import Effect, EffectContext
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.kernel_arrays import kernel_array
from mlsgalerkin.kernels import get_kernel, kernel_f_df
from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period, minimum_image

__all__ = ["SLIP_MODES", "Walls", "extrapolate_wall_state", "extrapolate_wall_state_reference",
           "no_slip_wall_velocity", "no_slip_wall_velocity_reference", "with_normal_component_of"]

SLIP_MODES = {"no_slip": 0, "free_slip": 1, "fixed": 2}

#: Smallest ``det P / Π diag P`` (1 for orthogonal basis functions, 0 for dependent ones) of the
#: no-slip fit's normal matrix ``P`` before it drops the curvature term, then the tangential slopes.
FIT_DETERMINANT_RATIO = 1e-6

#: A no-slip wall particle with a wall particle in reach whose normal is turned from its own by
#: more than ``arccos(CORNER_COSINE)`` (25°) is in a corner: no flat-wall fit, the Shepard mirror.
CORNER_COSINE = 0.9


@numba.njit(parallel=True, cache=True)
def _extrapolate(
    wall_ids, indptr, indices, x, v, rho, p, h, is_fluid, kid, support, dim, g_minus_a,
    wall_velocity, normals, slip, rho_ref, p_out, rho_out, v_out, period,
):
    for t in prange(wall_ids.shape[0]):
        w = wall_ids[t]
        # scalar accumulators (no per-particle heap allocation inside the parallel loop)
        sw = 0.0
        sp = 0.0
        sr = 0.0
        hyd = 0.0
        sv0 = 0.0
        sv1 = 0.0
        sv2 = 0.0
        for q in range(indptr[w], indptr[w + 1]):
            f = indices[q]
            if not is_fluid[f]:
                continue
            d0, d1, d2, r2 = pair_offset(x, w, f, period)   # x_fw; x_wf = −x_fw (exact)
            dwf = (-d0, -d1, -d2)
            wgt, _ = kernel_f_df(kid, np.sqrt(r2) / h[f], support, dim)
            if wgt <= 0.0:
                continue
            sw += wgt
            sp += p[f] * wgt
            sr += rho[f] * wgt
            for a in range(dim):
                hyd += g_minus_a[t, a] * rho[f] * dwf[a] * wgt
            sv0 += v[f, 0] * wgt
            sv1 += v[f, 1] * wgt
            if dim == 3:
                sv2 += v[f, 2] * wgt
        if sw > 0.0:
            p_out[t] = (sp + hyd) / sw
            rho_out[t] = sr / sw
            sv0 /= sw
            sv1 /= sw
            sv2 /= sw
        else:
            p_out[t] = 0.0
            rho_out[t] = rho_ref[t]
            sv0 = wall_velocity[t, 0]
            sv1 = wall_velocity[t, 1]
            sv2 = wall_velocity[t, 2] if dim == 3 else 0.0
        sv = (sv0, sv1, sv2)
        if slip == 0:
            for a in range(dim):
                v_out[t, a] = 2.0 * wall_velocity[t, a] - sv[a]
        elif slip == 1:
            vn = 0.0
            for a in range(dim):
                vn += (sv[a] - wall_velocity[t, a]) * normals[t, a]
            for a in range(dim):
                v_out[t, a] = sv[a] - 2.0 * vn * normals[t, a]
        else:
            for a in range(dim):
                v_out[t, a] = wall_velocity[t, a]


def extrapolate_wall_state(
    wall_ids: NDArray[np.int64], indptr: NDArray[np.int64], indices: NDArray[np.int32],
    x: NDArray[np.float64], v: NDArray[np.float64], rho: NDArray[np.float64], p: NDArray[np.float64],
    h: NDArray[np.float64], is_fluid: NDArray[np.bool_], kernel, g_minus_a: NDArray[np.float64],
    wall_velocity: NDArray[np.float64], normals: NDArray[np.float64], slip: str,
    rho_ref: NDArray[np.float64], period: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Wall pressure ``(n_w,)`` Pa, density ``(n_w,)`` kg/m³ and velocity ``(n_w, d)`` m/s.

    The ``"no_slip"`` velocity here is the Shepard mirror ``2 v_wall − ṽ_w`` (kept for
    comparison); :class:`Walls` takes the no-slip velocity from :func:`no_slip_wall_velocity`.

    ``wall_ids (n_w,)`` index the wall rows of the CSR neighbour table over all particles;
    ``x, v, rho, p, h, is_fluid`` are over all particles; ``g_minus_a`` is the gravity minus
    the wall's acceleration at each wall particle, ``(n_w, d)`` or ``(d,)`` for all (m/s²;
    gravity alone for fixed walls); ``wall_velocity, normals (n_w, d)``; ``rho_ref (n_w,)``;
    ``period (3,)`` m: minimum-image offsets along the periodic axes (default none).
    """
    n_w, dim = wall_ids.shape[0], x.shape[1]
    p_out = np.empty(n_w)
    rho_out = np.empty(n_w)
    v_out = np.empty((n_w, dim))
    g_minus_a = kernel_array(g_minus_a, np.float64, (n_w, dim))
    _extrapolate(
        wall_ids, indptr, indices, x, v, rho, p, h, is_fluid, kernel.kernel_id, kernel.support,
        dim, g_minus_a, wall_velocity, normals, SLIP_MODES[slip], rho_ref,
        p_out, rho_out, v_out, as_period(period),
    )
    return p_out, rho_out, v_out


def extrapolate_wall_state_reference(
    wall_ids, indptr, indices, x, v, rho, p, h, is_fluid, kernel, g_minus_a, wall_velocity, normals,
    slip, rho_ref, period=None,
):
    """Numpy version of :func:`extrapolate_wall_state` (tests)."""
    dim = x.shape[1]
    n_w = len(wall_ids)
    g_minus_a = np.broadcast_to(np.asarray(g_minus_a, dtype=float), (n_w, dim))
    p_out, rho_out, v_out = np.zeros(n_w), np.zeros(n_w), np.zeros((n_w, dim))
    for t, w in enumerate(wall_ids):
        nb = indices[indptr[w]:indptr[w + 1]]
        nb = nb[is_fluid[nb]]
        d = -minimum_image(x[nb] - x[w], as_period(period))
        W = kernel.shape(np.linalg.norm(d, axis=1) / h[nb], dim) if len(nb) else np.zeros(0)
        sw = W.sum()
        if sw > 0:
            p_out[t] = (W @ p[nb] + g_minus_a[t] @ ((rho[nb] * W) @ d)) / sw
            rho_out[t] = W @ rho[nb] / sw
            vt = W @ v[nb] / sw
        else:
            rho_out[t] = rho_ref[t]
            vt = wall_velocity[t]
        if slip == "no_slip":
            v_out[t] = 2 * wall_velocity[t] - vt
        elif slip == "free_slip":
            v_out[t] = vt - 2 * ((vt - wall_velocity[t]) @ normals[t]) * normals[t]
        else:
            v_out[t] = wall_velocity[t]
    return p_out, rho_out, v_out


@numba.njit(parallel=True, cache=True)
def _no_slip_velocity(wall_ids, indptr, indices, x, v, h, is_fluid, wall_index, kid, support, dim, spacing,
                      wall_velocity, normals, period, v_out, depth_out):
    for t in prange(wall_ids.shape[0]):
        w = wall_ids[t]
        n0 = normals[t, 0]
        n1 = normals[t, 1] if dim > 1 else 0.0
        n2 = normals[t, 2] if dim > 2 else 0.0
        # the wall particle of this one's column nearest the fluid (largest offset along n)
        # and whether a wall particle in reach faces another way (a corner: no flat-wall fit)
        top = w
        top_proj = 0.0
        corner = False
        reach2 = (support * h[w]) ** 2
        for q in range(indptr[w], indptr[w + 1]):
            j = indices[q]
            if j == w or wall_index[j] < 0:
                continue
            d0, d1, d2, r2 = pair_offset(x, w, j, period)          # x_j − x_w
            proj = d0 * n0 + d1 * n1 + d2 * n2
            lateral2 = r2 - proj * proj
            if proj > top_proj and lateral2 < (0.25 * spacing) ** 2:
                top, top_proj = j, proj
            if r2 < reach2:
                tj = wall_index[j]
                cos = normals[tj, 0] * n0
                if dim > 1:
                    cos += normals[tj, 1] * n1
                if dim > 2:
                    cos += normals[tj, 2] * n2
                if cos < CORNER_COSINE:
                    corner = True
        depth = top_proj + 0.5 * spacing
        depth_out[t] = depth
        # x_s − x_top: the surface point, half a spacing beyond the top particle along n
        e0, e1, e2, _ = pair_offset(x, w, top, period)
        s0 = depth * n0 - e0
        s1 = depth * n1 - e1
        s2 = depth * n2 - e2
        # weighted least squares over the fluid in reach of the top particle, in units of the
        # spacing: v_f − v_wall ≈ B ρ + c (ρ·n)², ρ = (x_f − x_s)/Δx; basis (ρ_0 … ρ_{d−1}, (ρ·n)²)
        m = dim + 1
        du2_max = 0.0
        P = np.zeros((m, m))
        Q = np.zeros((m, dim))
        phi = np.zeros(m)
        for q in range(indptr[top], indptr[top + 1]):
            f = indices[q]
            if not is_fluid[f]:
                continue
            d0, d1, d2, r2 = pair_offset(x, top, f, period)        # x_f − x_top
            wgt, _ = kernel_f_df(kid, np.sqrt(r2) / h[f], support, dim)
            if wgt <= 0.0:
                continue
            rho0 = (d0 - s0) / spacing
            rho1 = (d1 - s1) / spacing
            rho2 = (d2 - s2) / spacing
            phi[0] = rho0
            if dim > 1:
                phi[1] = rho1
            if dim > 2:
                phi[2] = rho2
            rn = rho0 * n0 + rho1 * n1 + rho2 * n2
            phi[dim] = rn * rn
            du2 = 0.0
            for a in range(m):
                for b in range(m):
                    P[a, b] += wgt * phi[a] * phi[b]
                for b in range(dim):
                    Q[a, b] += wgt * phi[a] * (v[f, b] - wall_velocity[t, b])
            for b in range(dim):
                du2 += (v[f, b] - wall_velocity[t, b]) ** 2
            if du2 > du2_max:
                du2_max = du2
        # at the particle, ρ = −(d_w/Δx) n: the basis there
        dn = depth / spacing
        phi[0] = -dn * n0
        if dim > 1:
            phi[1] = -dn * n1
        if dim > 2:
            phi[2] = -dn * n2
        phi[dim] = dn * dn
        value = np.zeros(dim)
        # too few fluid points for the curvature, nor for the linear fit: the normal slope alone
        if not _fit_at(P, Q, phi, m, dim, value) and not _fit_at(P, Q, phi, dim, dim, value):
            ann = 0.0
            for a in range(dim):
                for b in range(dim):
                    ann += normals[t, a] * P[a, b] * normals[t, b]
            for b in range(dim):
                qn = 0.0
                for a in range(dim):
                    qn += normals[t, a] * Q[a, b]
                value[b] = -dn * qn / ann if ann > 0.0 else 0.0
        # a fit that continues the fluid to more than 2 d_w/Δx times its largest velocity
        # relative to the wall (a splash, a corner) is not trusted: the Shepard mirror instead
        size2 = 0.0
        for b in range(dim):
            size2 += value[b] * value[b]
        if corner or size2 > (2.0 * dn) ** 2 * du2_max:
            sw = 0.0
            for b in range(dim):
                value[b] = 0.0
            for q in range(indptr[w], indptr[w + 1]):
                f = indices[q]
                if not is_fluid[f]:
                    continue
                _, _, _, r2 = pair_offset(x, w, f, period)
                wgt, _ = kernel_f_df(kid, np.sqrt(r2) / h[f], support, dim)
                if wgt <= 0.0:
                    continue
                sw += wgt
                for b in range(dim):
                    value[b] -= wgt * (v[f, b] - wall_velocity[t, b])
            for b in range(dim):
                value[b] = value[b] / sw if sw > 0.0 else 0.0
        for b in range(dim):
            v_out[t, b] = wall_velocity[t, b] + value[b]


@numba.njit(cache=True)
def _fit_at(P, Q, phi, k, dim, value):
    """``value = phi[:k] · P[:k, :k]⁻¹ Q[:k]`` by a Cholesky factorisation, if ``P[:k, :k]`` is
    positive definite with ``det / Π diag`` at least :data:`FIT_DETERMINANT_RATIO` (returns True)."""
    C = np.zeros((k, k))
    ratio = 1.0
    for i in range(k):
        for j in range(i + 1):
            acc = P[i, j]
            for r in range(j):
                acc -= C[i, r] * C[j, r]
            if i == j:
                if acc <= 0.0 or P[i, i] <= 0.0:
                    return False
                ratio *= acc / P[i, i]
                C[i, i] = np.sqrt(acc)
            else:
                C[i, j] = acc / C[j, j]
    if ratio < FIT_DETERMINANT_RATIO:
        return False
    y = np.zeros(k)       # P y = phi: forward then backward substitution
    for i in range(k):
        acc = phi[i]
        for r in range(i):
            acc -= C[i, r] * y[r]
        y[i] = acc / C[i, i]
    for i in range(k - 1, -1, -1):
        acc = y[i]
        for r in range(i + 1, k):
            acc -= C[r, i] * y[r]
        y[i] = acc / C[i, i]
    for b in range(dim):
        acc = 0.0
        for a in range(k):
            acc += y[a] * Q[a, b]
        value[b] = acc
    return True


def no_slip_wall_velocity(
    wall_ids: NDArray[np.int64], indptr: NDArray[np.int64], indices: NDArray[np.int32],
    x: NDArray[np.float64], v: NDArray[np.float64], h: NDArray[np.float64], is_fluid: NDArray[np.bool_],
    kernel, spacing: float, wall_velocity: NDArray[np.float64], normals: NDArray[np.float64],
    period: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """No-slip wall-particle velocities ``(n_w, d)`` m/s and depths ``(n_w,)`` m (module docstring).

    Each wall particle's depth ``d_w`` behind the wall surface is ``Δx/2`` plus the largest
    offset along its normal of a wall particle of its column (lateral offset below ``Δx/4``);
    the fluid velocity is fitted, by weighted least squares over the fluid in reach of the
    column's top particle (weights ``W(|x_f − x_top|, h_f)``), as ``v_wall + B (x − x_s)``
    with ``x_s = x_w + d_w n`` the particle's foot on the surface; the particle gets
    ``v_w = v_wall − d_w B n``, the linear continuation through the no-slip value. Arguments as
    :func:`extrapolate_wall_state`; ``spacing`` (m) the wall particles' ``Δx``.
    """
    n_w, dim = wall_ids.shape[0], x.shape[1]
    wall_index = np.full(x.shape[0], -1, dtype=np.int64)
    wall_index[wall_ids] = np.arange(n_w)
    v_out = np.empty((n_w, dim))
    depth = np.empty(n_w)
    _no_slip_velocity(wall_ids, indptr, indices, x, v, h, is_fluid, wall_index, kernel.kernel_id, kernel.support, dim,
                      float(spacing), wall_velocity, normals, as_period(period), v_out, depth)
    return v_out, depth


def no_slip_wall_velocity_reference(wall_ids, indptr, indices, x, v, h, is_fluid, kernel, spacing, wall_velocity,
                                    normals, period=None):
    """Numpy version of :func:`no_slip_wall_velocity` (tests)."""
    n_w, dim = len(wall_ids), x.shape[1]
    per = as_period(period)
    wall_index = np.full(x.shape[0], -1, dtype=np.int64)
    wall_index[wall_ids] = np.arange(n_w)
    v_out, depth = np.zeros((n_w, dim)), np.zeros(n_w)
    for t, w in enumerate(wall_ids):
        n = normals[t]
        nb = indices[indptr[w]:indptr[w + 1]]
        nb = nb[(wall_index[nb] >= 0) & (nb != w)]
        d = minimum_image(x[nb] - x[w], per)
        proj = d @ n
        near = np.einsum("id,id->i", d, d) < (kernel.support * h[w]) ** 2
        corner = bool(np.any(normals[wall_index[nb[near]]] @ n < CORNER_COSINE))
        ok = (proj > 0) & (np.einsum("id,id->i", d, d) - proj**2 < (0.25 * spacing) ** 2)
        if ok.any():
            k = np.flatnonzero(ok)[np.argmax(proj[ok])]
            top, top_off, top_proj = nb[k], d[k], proj[k]
        else:
            top, top_off, top_proj = w, np.zeros(dim), 0.0
        depth[t] = top_proj + 0.5 * spacing
        s = depth[t] * n - top_off
        fl = indices[indptr[top]:indptr[top + 1]]
        fl = fl[is_fluid[fl]]
        df = minimum_image(x[fl] - x[top], per)
        W = kernel.shape(np.linalg.norm(df, axis=1) / h[fl], dim) if len(fl) else np.zeros(0)
        keep = W > 0
        W, rho = W[keep], (df[keep] - s) / spacing
        basis = np.column_stack([rho, (rho @ n) ** 2])
        P = basis.T @ (W[:, None] * basis)
        Q = basis.T @ (W[:, None] * (v[fl[keep]] - wall_velocity[t]))
        dn = depth[t] / spacing
        at = np.concatenate([-dn * n, [dn * dn]])
        for k in (dim + 1, dim):
            A = P[:k, :k]
            diag = np.diag(A)
            if np.all(diag > 0) and np.linalg.det(A) / np.prod(diag) >= FIT_DETERMINANT_RATIO:
                v_out[t] = wall_velocity[t] + at[:k] @ np.linalg.solve(A, Q[:k])
                break
        else:
            ann = n @ P[:dim, :dim] @ n
            v_out[t] = wall_velocity[t] - (dn * (n @ Q[:dim]) / ann if ann > 0 else 0.0)
        du2_max = np.max(np.sum((v[fl[keep]] - wall_velocity[t]) ** 2, axis=1)) if keep.any() else 0.0
        if corner or np.sum((v_out[t] - wall_velocity[t]) ** 2) > (2.0 * dn) ** 2 * du2_max:   # Shepard mirror
            own = indices[indptr[w]:indptr[w + 1]]
            own = own[is_fluid[own]]
            Wo = kernel.shape(np.linalg.norm(minimum_image(x[own] - x[w], per), axis=1) / h[own], dim) \
                if len(own) else np.zeros(0)
            sw = Wo.sum()
            v_out[t] = wall_velocity[t] - (Wo @ (v[own] - wall_velocity[t]) / sw if sw > 0 else 0.0)
    return v_out, depth


def with_normal_component_of(v: NDArray[np.float64], v_normal: NDArray[np.float64],
                             normals: NDArray[np.float64]) -> NDArray[np.float64]:
    """``v − (v·n) n + (v_normal·n) n`` per row (m/s, shapes ``(n_w, d)``): the tangential part of
    ``v`` with the normal part of ``v_normal`` (the no-slip fit's tangential continuation with the
    free-slip mirror's normal component, module docstring)."""
    n = normals[:, :v.shape[1]]
    return v + np.sum((v_normal - v) * n, axis=1)[:, None] * n


class Walls(Effect):
    """Wall particles of the fluid approximation: extrapolated pressure, density and velocity
    (module docstring). ``slip`` is ``"free_slip"`` (default), ``"no_slip"`` or ``"fixed"``.

    The hydrostatic term of the wall pressure uses ``state.gravity`` (zero without a listed
    :class:`~mlsgalerkin.fluid.gravity.Gravity`) minus the acceleration of each wall particle
    (``state.wall_acceleration``, non-zero for a wall with a prescribed motion).
    """

    name = "walls"
    stages = ("kinematics", "boundary")
    reads = ("velocity", "pressure", "density", "neighbors")
    provides = ("wall_state",)

    def __init__(self, slip: str = "free_slip") -> None:
        self.slip = slip

    def __repr__(self) -> str:
        return f"Walls(slip={self.slip!r})"

    def check(self, ctx: EffectContext) -> list[str]:
        problems = []
        walls = [w for w in ctx.bodies_of(WallBody) if w.n]
        if self.slip not in SLIP_MODES:
            problems.append(f"Walls: slip must be one of {sorted(SLIP_MODES)}, got {self.slip!r}")
        if not walls:
            problems.append("Walls: the scene has no WallBody with wall particles; add one or remove the effect (a "
                            "wall of only a penalty surface needs PenaltyWalls, not Walls)")
        if self.slip in ("free_slip", "no_slip") and any(w.normals is None for w in walls):
            problems.append(f"Walls: {self.slip} needs wall normals (WallBody(normals=...)); "
                            "wall_box() and WallBody.on_surface() provide them")
        return problems

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        self._kernel = get_kernel(ctx.approximation.kernel)
        self._ids = np.arange(state.n_fluid, state.n, dtype=np.int64)
        self._is_fluid = np.zeros(state.n, dtype=bool)
        self._is_fluid[state.fluid] = True
        self._rho_ref = state.rho0[state.walls].copy()

    def _extrapolate(self, s: FluidState, slip: str | None = None):
        nb = s.neighbors
        g = s.gravity if s.gravity is not None else np.zeros(s.dim)
        return extrapolate_wall_state(
            self._ids, nb.indptr, nb.indices, s.x, s.v, s.rho, s.p, s.h, self._is_fluid, self._kernel,
            g - s.wall_acceleration, s.wall_velocity, s.wall_normals, slip or self.slip, self._rho_ref, s.period,
        )

    def kinematics(self, s: FluidState) -> None:
        if not s.n_walls:
            return
        if self.slip == "no_slip":
            nb = s.neighbors
            v_w, _ = no_slip_wall_velocity(self._ids, nb.indptr, nb.indices, s.x, s.v, s.h, self._is_fluid,
                                           self._kernel, s.spacing, s.wall_velocity, s.wall_normals, s.period)
            _, _, v_mirror = self._extrapolate(s, "free_slip")
            v_w = with_normal_component_of(v_w, v_mirror, s.wall_normals)
        else:
            _, _, v_w = self._extrapolate(s)
        s.v[s.walls] = v_w

    def boundary(self, s: FluidState) -> None:
        if s.n_walls:
            p_w, rho_w, _ = self._extrapolate(s)
            w = s.walls
            s.p[w] = p_w
            s.rho[w] = rho_w
            s.M[w] = rho_w * s.wall_volume
