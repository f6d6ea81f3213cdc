r"""Viscous stresses entered in the Galerkin weak form: Newtonian viscosity and bulk artificial
viscosity. Both add to the stress ``σ`` of each integration point, so the Galerkin sum
``−Σ_k σ_k ∇N_i(x_k) V_k`` conserves linear momentum (and angular momentum: both are symmetric)."""

from __future__ import annotations

import numpy as np

from mlsgalerkin.fluid.bodies import FluidBody
from mlsgalerkin.fluid.effect import Effect, EffectContext, check_nonnegative
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.fluid.time_step import bulk_viscosity_limit, viscous_limit
from mlsgalerkin.fluid.viscous_stabilisation import viscous_residual_force
from mlsgalerkin.kernels import get_kernel

__all__ = ["BulkViscosity", "NewtonianViscosity"]


class NewtonianViscosity(Effect):
    r"""Newtonian viscous stress ``σ += μ (L + Lᵀ − ⅔ tr L I)`` with each phase's viscosity ``μ`` (Pa s).

    Wall integration points take the viscosity of the first phase. Time-step limit:
    ``0.125 h²/ν``, ``ν = μ/ρ0`` (:func:`~mlsgalerkin.fluid.time_step.viscous_limit`).

    With ``stabilised=True`` (the default) the fluid particles also get the pair force of
    :mod:`~mlsgalerkin.fluid.viscous_stabilisation` on the velocity residual
    ``v_i − v_j − ½(L_i + L_j) x_ij``: zero for a linear velocity field, it gives the modes the
    nodal gradients cannot see (a row-to-row alternation) their viscous damping.
    ``stabilised=False`` is the plain nodal term.
    """

    name = "newtonian_viscosity"
    stages = ("stress", "force")
    reads = ("velocity_gradient",)

    def __init__(self, factor: float = 0.125, *, stabilised: bool = True) -> None:
        self.factor = factor
        self.stabilised = bool(stabilised)

    def __repr__(self) -> str:
        return "NewtonianViscosity()" if self.stabilised else "NewtonianViscosity(stabilised=False)"

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        self._kernel = get_kernel(ctx.approximation.kernel)
        self._active = np.zeros(state.n, dtype=bool)
        self._active[state.fluid] = True

    def check(self, ctx: EffectContext) -> list[str]:
        if not any(ph.viscosity > 0 for b in ctx.bodies_of(FluidBody) for ph in b.phases):
            return ["NewtonianViscosity: every phase has zero viscosity; set Phase(viscosity=...) "
                    "or remove the effect"]
        return []

    def stress(self, s: FluidState) -> None:
        L = s.L
        d = s.dim
        D = L + np.swapaxes(L, 1, 2)
        tr = np.trace(L, axis1=1, axis2=2)
        for a in range(d):
            D[:, a, a] -= (2.0 / 3.0) * tr
        s.stress += s.mu[:, None, None] * D

    def force(self, s: FluidState) -> None:
        if not self.stabilised:
            return
        nb = s.neighbors
        f = viscous_residual_force(s.x, s.v, s.L, s.mu, s.M / s.rho, s.h, nb.indptr, nb.indices, self._kernel,
                                   self._active, s.period)
        s.force[s.fluid] += f[s.fluid]

    def time_step_limit(self, s: FluidState) -> float:
        f = s.fluid
        return viscous_limit(s.h[f], s.mu[f] / s.rho0[f], self.factor)


class BulkViscosity(Effect):
    r"""Bulk artificial viscosity entered as a pressure-like stress ``σ −= q I``:

    ``q = ρ (a_L h c |∇·v| + a_N h² (∇·v)²)`` where ``∇·v < 0`` (compression), else 0 —
    the linear and von Neumann–Richtmyer terms (von Neumann & Richtmyer 1950) with ``h`` for
    ``Δx``. It acts on compression only and cannot see velocity modes with zero discrete
    divergence (see the theory page). Time-step limit: the diffusion number of ``ν_b = a_L h c``
    (:func:`~mlsgalerkin.fluid.time_step.bulk_viscosity_limit`).
    """

    name = "bulk_viscosity"
    stages = ("stress",)
    reads = ("velocity_gradient", "sound_speed", "density")

    def __init__(self, linear: float = 0.5, quadratic: float = 1.0) -> None:
        self.linear, self.quadratic = linear, quadratic

    def __repr__(self) -> str:
        return f"BulkViscosity(linear={self.linear:g}, quadratic={self.quadratic:g})"

    def check(self, ctx: EffectContext) -> list[str]:
        problems: list[str] = []
        check_nonnegative("BulkViscosity", "linear", self.linear, problems)
        check_nonnegative("BulkViscosity", "quadratic", self.quadratic, problems)
        return problems

    def stress(self, s: FluidState) -> None:
        f = s.fluid
        div = np.trace(s.L[f], axis1=1, axis2=2)
        comp = np.minimum(div, 0.0)
        h = s.h[f]
        q = s.rho[f] * (self.linear * h * s.c[f] * (-comp) + self.quadratic * h * h * comp * comp)
        for a in range(s.dim):
            s.stress[f, a, a] -= q

    def time_step_limit(self, s: FluidState) -> float:
        f = s.fluid
        return bulk_viscosity_limit(s.h[f], s.c[f], self.linear)
