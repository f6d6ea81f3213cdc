r"""Density diffusion in the collocated continuity equation: the :class:`DensityDiffusion` effect
and its kernel (δ-SPH; Molteni & Colagrossi 2009, Antuono et al. 2010, Fourtakas et al. 2019).

The continuity equation collocated at the particles, ``ρ̇_i = −ρ_i tr L_i``, carries no
dissipation of its own: high-frequency density (and so pressure) noise, the checkerboard
that nodal integration does not see, is never damped. A diffusive term is added,

.. math::
    \dot\rho_i \mathrel{+}= \delta\, h_i\, c_0\, \rho_{0,i} \sum_j \psi_{ij}\,
        \frac{\mathbf x_{ji}\cdot\nabla_i W_{ij}}{|\mathbf x_{ji}|^2 + \eta^2}\, V_j,
    \qquad \eta^2 = 0.01\,h_{ij}^2,

over the fluid neighbours ``j`` of the particle's own phase (``x_ji = x_j − x_i``,
``V_j = M_j/ρ_j``, ``x_ji·∇_iW_ij = −r W'(r) ≥ 0``), acting on the density ratio
``r = ρ/ρ0`` so a density jump between phases is never smoothed. The flux ``ψ_ij``:

``"gradient"`` (default; Antuono et al. 2010)
    :math:`\psi_{ij} = 2(r_j - r_i) - (\langle\nabla r\rangle_i + \langle\nabla r\rangle_j)\cdot\mathbf x_{ji}`
    with the corrected gradients of :mod:`~mlsgalerkin.fluid.corrected_gradient`: a linear
    density field (hydrostatic) gives ``ψ = 0`` exactly, also at the free surface and walls,
    so only the deviation from a linear field diffuses.
``"hydrostatic"`` (Fourtakas et al. 2019)
    :math:`\psi_{ij} = 2[(r_j - r_i) - r^H_{ji}]`,
    :math:`r^H_{ji} = (1 + \gamma\,\mathbf g\cdot\mathbf x_{ji}/c_0^2)^{1/\gamma} - 1`: the
    hydrostatic difference of the Tait ratio is subtracted (no gradients needed; exact for a
    fluid at hydrostatic rest only).
``"none"`` (Molteni & Colagrossi 2009)
    :math:`\psi_{ij} = 2(r_j - r_i)`: diffuses the hydrostatic gradient too (a fluid at rest
    drifts; kept for the ablation).

The term is conservative (antisymmetric in ``i, j`` for equal volumes: it moves density, not
mass — the particle masses stay constant) and adds no momentum. It acts like a diffusion of
coefficient ``ν_ρ ≈ δ h c0 / 2`` on the density only; the momentum equation is untouched, so it
costs no Reynolds number. Default ``δ = 0.1`` (Antuono et al. 2010). Its explicit limit
``Δt ≤ 0.125 h/(δ c0)`` (:func:`~mlsgalerkin.fluid.time_step.density_diffusion_limit`) is 3
times the acoustic limit for ``δ = 0.1``. A numba kernel with a numpy reference.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

from mlsgalerkin.fluid.corrected_gradient import GRADIENT_FIELD, ratio_gradient, ratio_gradient_mls
from mlsgalerkin.fluid.effect import Effect, EffectContext, check_positive
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.fluid.time_step import density_diffusion_limit
from mlsgalerkin.kernels import get_kernel, kernel_f_df
from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period, minimum_image

__all__ = ["CORRECTIONS", "DensityDiffusion", "density_diffusion_rate", "density_diffusion_rate_reference"]

#: The fluxes ψ (module docstring), by name.
CORRECTIONS = {"gradient": 0, "hydrostatic": 1, "none": 2}
#: How the ``"gradient"`` correction forms ⟨∇r⟩: ``"mls"`` (default; the MLS gradient of the
#: pressure, :func:`~mlsgalerkin.fluid.corrected_gradient.ratio_gradient_mls`) or ``"kernel"``
#: (Antuono et al. 2010's renormalised kernel gradient over same-phase fluid neighbours,
#: :func:`~mlsgalerkin.fluid.corrected_gradient.ratio_gradient`, a second pass over the pairs).
GRADIENTS = ("mls", "kernel")

ETA_SQUARED = 0.01


@numba.njit(parallel=True, cache=True)
def _diffusion(x, ratio, rho0, volume, h, phase, indptr, indices, n_fluid, kid, support, norm_d, delta, c0,
               mode, grad, gravity, gamma, out, period):
    dim = x.shape[1]
    for i in prange(n_fluid):
        acc = 0.0
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if j == i or j >= n_fluid or phase[j] != phase[i]:
                continue
            d0, d1, d2, r2 = pair_offset(x, i, j, period)   # x_ji = x_j − x_i
            if r2 <= 0.0:
                continue
            hij = 0.5 * (h[i] + h[j])
            r = math.sqrt(r2)
            qq = r / hij
            if qq >= support:
                continue
            _, df = kernel_f_df(kid, qq, support, dim)
            xgw = -r * norm_d / hij ** (dim + 1) * df          # x_ji · ∇_i W_ij ≥ 0
            psi = 2.0 * (ratio[j] - ratio[i])
            if mode == 0:
                gs = (grad[i, 0] + grad[j, 0]) * d0 + (grad[i, 1] + grad[j, 1]) * d1
                if dim == 3:
                    gs += (grad[i, 2] + grad[j, 2]) * d2
                psi -= gs
            elif mode == 1:
                gx = gravity[0] * d0 + gravity[1] * d1
                if dim == 3:
                    gx += gravity[2] * d2
                base = 1.0 + gamma * gx / (c0 * c0)
                if base > 0.0:
                    psi -= 2.0 * (base ** (1.0 / gamma) - 1.0)
            acc += psi * xgw / (r2 + ETA_SQUARED * hij * hij) * volume[j]
        out[i] = delta * h[i] * c0 * rho0[i] * acc


def density_diffusion_rate(
    x: NDArray[np.float64], rho: NDArray[np.float64], rho0: NDArray[np.float64], M: NDArray[np.float64],
    h: NDArray[np.float64], phase: NDArray[np.int64], indptr: NDArray[np.int64], indices: NDArray[np.int32],
    n_fluid: int, kernel, delta: float, c0: float, correction: str = "gradient",
    gravity: NDArray[np.float64] | None = None, gamma: float = 7.0, grad: NDArray[np.float64] | None = None,
    period: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """The diffusive term ``(n_fluid,)`` of ``ρ̇`` (kg/m³/s) of the fluid particles (module
    docstring). Arrays over all ``n`` particles (fluid first): ``x (n, d)`` m, ``rho, rho0``
    kg/m³, ``M`` kg, ``h`` m, ``phase``; the CSR neighbour table of the particles against
    themselves; ``c0`` m/s; ``gravity (d,)`` m/s² for ``correction="hydrostatic"``; ``period (3,)``
    m, the minimum image along periodic axes (:mod:`mlsgalerkin.periodic`; default none)."""
    dim = x.shape[1]
    ratio = rho / rho0
    volume = M / rho
    mode = CORRECTIONS[correction]
    period = as_period(period)
    if mode == 0:
        if grad is None:
            grad, _ = ratio_gradient(x, ratio, volume, h, phase, indptr, indices, n_fluid, kernel, period)
    else:
        grad = np.zeros((n_fluid, dim))
    g = np.zeros(3) if gravity is None else np.concatenate([np.asarray(gravity, dtype=float), np.zeros(3 - dim)])
    out = np.empty(n_fluid)
    _diffusion(x, ratio, rho0, volume, h, phase, indptr, indices, n_fluid, kernel.kernel_id, float(kernel.support),
               float(kernel.normalisation(dim)), float(delta), float(c0), mode, grad, g, float(gamma), out, period)
    return out


def density_diffusion_rate_reference(x, rho, rho0, M, h, phase, indptr, indices, n_fluid, kernel, delta, c0,
                                     correction="gradient", gravity=None, gamma=7.0, period=None):
    """Numpy version of :func:`density_diffusion_rate` (tests)."""
    from mlsgalerkin.fluid.corrected_gradient import ratio_gradient_reference

    dim = x.shape[1]
    ratio = rho / rho0
    volume = M / rho
    if correction == "gradient":
        grad, _ = ratio_gradient_reference(x, ratio, volume, h, phase, indptr, indices, n_fluid, kernel, period)
    out = np.zeros(n_fluid)
    for i in range(n_fluid):
        nb = indices[indptr[i]:indptr[i + 1]].astype(np.int64)
        nb = nb[(nb != i) & (nb < n_fluid)]
        nb = nb[phase[nb] == phase[i]]
        xji = minimum_image(x[nb] - x[i], as_period(period))
        r = np.linalg.norm(xji, axis=1)
        hij = 0.5 * (h[i] + h[nb])
        keep = (r > 0) & (r < kernel.support * hij)
        nb, xji, r, hij = nb[keep], xji[keep], r[keep], hij[keep]
        xgw = -r * kernel.derivative(r, hij, dim)
        psi = 2.0 * (ratio[nb] - ratio[i])
        if correction == "gradient":
            psi -= np.einsum("pd,pd->p", grad[i] + grad[nb], xji)
        elif correction == "hydrostatic":
            base = 1.0 + gamma * (xji @ np.asarray(gravity, dtype=float)) / c0**2
            psi -= np.where(base > 0, 2.0 * (np.maximum(base, 0) ** (1 / gamma) - 1.0), 0.0)
        out[i] = delta * h[i] * c0 * rho0[i] * np.sum(psi * xgw / (r**2 + ETA_SQUARED * hij**2) * volume[nb])
    return out


class DensityDiffusion(Effect):
    r"""δ-SPH density diffusion in the continuity equation (module docstring):
    ``ρ̇_i += δ h c0 ρ0 Σ_j ψ_ij x_ji·∇W_ij/(r² + η²) V_j`` over same-phase fluid pairs.

    ``delta`` (default 0.1), ``correction`` ``"gradient"`` (Antuono et al. 2010, default),
    ``"hydrostatic"`` (Fourtakas et al. 2019; needs ``Gravity``) or ``"none"`` (Molteni &
    Colagrossi 2009). ``c0`` is the pressure model's reference sound speed.
    """

    name = "density_diffusion"
    stabilising = True
    stages = ("continuity",)
    reads = ("density", "neighbors", "sound_speed")
    provides = (GRADIENT_FIELD,)

    def __init__(self, delta: float = 0.1, correction: str = "gradient", gradient: str = "mls") -> None:
        self.delta, self.correction, self.gradient = delta, correction, gradient
        self.c0 = math.nan
        self._h = math.nan

    def __repr__(self) -> str:
        return f"DensityDiffusion(delta={self.delta:g}, correction={self.correction!r}, gradient={self.gradient!r})"

    def check(self, ctx: EffectContext) -> list[str]:
        problems: list[str] = []
        check_positive("DensityDiffusion", "delta", self.delta, problems)
        if self.gradient not in GRADIENTS:
            problems.append(f"DensityDiffusion: gradient must be one of {list(GRADIENTS)}, got {self.gradient!r}")
        if self.correction not in CORRECTIONS:
            problems.append(f"DensityDiffusion: correction must be one of {sorted(CORRECTIONS)}, got "
                            f"{self.correction!r}")
        if ctx.sound_speed() is None:
            problems.append("DensityDiffusion needs a pressure model with a reference sound speed c0 "
                            "(TaitPressure)")
        if self.correction == "hydrostatic" and not ctx.provides("gravity"):
            problems.append("DensityDiffusion(correction='hydrostatic') subtracts the hydrostatic density "
                            "difference: list Gravity, or use correction='gradient'")
        return problems

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        self._kernel = get_kernel(ctx.approximation.kernel)
        self.c0 = state.c0
        self._gamma = state.gamma
        self._h = float(state.h[state.fluid].max()) if state.n_fluid else math.nan
        if self.correction == "gradient":
            state.extra[GRADIENT_FIELD] = np.zeros_like(state.x)

    def continuity(self, s: FluidState) -> None:
        nb = s.neighbors
        grad = None
        if self.correction == "gradient" and self.gradient == "mls":
            grad = ratio_gradient_mls(s.table, s.rho, s.rho0, s.p, s.n_fluid, self.c0, self._gamma)
        elif self.correction == "gradient":
            grad, _ = ratio_gradient(s.x, s.rho / s.rho0, s.M / s.rho, s.h, s.phase, nb.indptr, nb.indices,
                                     s.n_fluid, self._kernel, s.period)
        if grad is not None:
            full = s.extra.get(GRADIENT_FIELD)
            if full is None or full.shape != s.x.shape:
                full = s.extra[GRADIENT_FIELD] = np.zeros_like(s.x)
            full[s.fluid] = grad
        rate = density_diffusion_rate(
            s.x, s.rho, s.rho0, s.M, s.h, s.phase, nb.indptr, nb.indices, s.n_fluid, self._kernel,
            self.delta, self.c0, self.correction, s.gravity, self._gamma, grad=grad, period=s.period,
        )
        s.drho[s.fluid] += rate

    def time_step_limit(self, s: FluidState) -> float:
        f = s.fluid
        return density_diffusion_limit(s.h[f], self.delta, self.c0)

    def summary(self) -> dict[str, Any]:
        return {"delta": self.delta, "correction": self.correction, "gradient": self.gradient, "c0": self.c0,
                "density_diffusivity_m2_per_s": 0.5 * self.delta * self._h * self.c0}
