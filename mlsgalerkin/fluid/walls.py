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

- ``"no_slip"``: ``v_w = 2 v_wall − ṽ_w`` (the MLS velocity vanishes on the wall surface);
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
from mlsgalerkin.kernels import get_kernel, kernel_f_df
from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period, minimum_image

__all__ = ["SLIP_MODES", "Walls", "extrapolate_wall_state", "extrapolate_wall_state_reference"]

SLIP_MODES = {"no_slip": 0, "free_slip": 1, "fixed": 2}


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
    g_minus_a = np.ascontiguousarray(np.broadcast_to(np.asarray(g_minus_a, dtype=float), (n_w, dim)))
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
        if self.slip == "free_slip" and any(w.normals is None for w in walls):
            problems.append("Walls: free_slip needs wall normals (WallBody(normals=...)); "
                            "wall_box() provides them")
        return problems

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        self._kernel = get_kernel(ctx.approximation.kernel)
        self._ids = np.arange(state.n_fluid, state.n, dtype=np.int64)
        self._is_fluid = np.zeros(state.n, dtype=bool)
        self._is_fluid[state.fluid] = True
        self._rho_ref = state.rho0[state.walls].copy()

    def _extrapolate(self, s: FluidState):
        nb = s.neighbors
        g = s.gravity if s.gravity is not None else np.zeros(s.dim)
        return extrapolate_wall_state(
            self._ids, nb.indptr, nb.indices, s.x, s.v, s.rho, s.p, s.h, self._is_fluid, self._kernel,
            g - s.wall_acceleration, s.wall_velocity, s.wall_normals, self.slip, self._rho_ref, s.period,
        )

    def kinematics(self, s: FluidState) -> None:
        if s.n_walls:
            _, _, v_w = self._extrapolate(s)
            s.v[s.walls] = v_w

    def boundary(self, s: FluidState) -> None:
        if s.n_walls:
            p_w, rho_w, _ = self._extrapolate(s)
            w = s.walls
            s.p[w] = p_w
            s.rho[w] = rho_w
            s.M[w] = rho_w * s.wall_volume
