r"""Viscous stresses entered in the Galerkin weak form: Newtonian viscosity and bulk artificial
viscosity. Both add to the stress ``σ`` of each integration point, so the Galerkin sum
``−Σ_k σ_k ∇N_i(x_k) V_k`` conserves linear momentum (and angular momentum: both are symmetric)."""

from __future__ import annotations

import numpy as np

from mlsgalerkin.fluid.bodies import FluidBody
from mlsgalerkin.fluid.effect import Effect, EffectContext, check_nonnegative
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.fluid.time_step import bulk_viscosity_limit, viscous_limit

__all__ = ["BulkViscosity", "NewtonianViscosity"]


class NewtonianViscosity(Effect):
    r"""Newtonian viscous stress ``σ += μ (L + Lᵀ − ⅔ tr L I)`` with each phase's viscosity ``μ`` (Pa s).

    Wall integration points take the viscosity of the first phase. Time-step limit:
    ``0.125 h²/ν``, ``ν = μ/ρ0`` (:func:`~mlsgalerkin.fluid.time_step.viscous_limit`).
    """

    name = "newtonian_viscosity"
    stages = ("stress",)
    reads = ("velocity_gradient",)

    def __init__(self, factor: float = 0.125) -> None:
        self.factor = factor

    def __repr__(self) -> str:
        return "NewtonianViscosity()"

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
