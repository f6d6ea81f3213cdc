"""Uniform gravity: the body force of the fluid, and the ``gravity`` quantity of the state."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from mlsgalerkin.fluid.effect import Effect, EffectContext
from mlsgalerkin.fluid.state import FluidState

__all__ = ["Gravity"]


class Gravity(Effect):
    """Uniform gravity ``g`` (m/s²): nodal force ``f_i = m_i g`` with ``m`` the mass in use.

    With the lumped mass this is exactly the Galerkin body force ``Σ_k N_i(x_k) ρ_k g V_k``
    (because ``ρ_k V_k = M_k``); with ``mass="particle"`` it is ``M_i g``; with the consistent
    mass the right-hand side is the lumped vector and the solve returns ``a = g``. Provides
    ``gravity``: ``state.gravity`` holds ``g``, read by the wall pressure (the hydrostatic
    term) and the potential energy of the time series.
    """

    name = "gravity"
    stages = ("force",)
    reads = ("mass",)
    provides = ("gravity",)

    def __init__(self, g: ArrayLike = (0.0, -9.81)) -> None:
        self.g = np.asarray(g, dtype=float)

    def __repr__(self) -> str:
        return f"Gravity(g={self.g.tolist()})"

    def check(self, ctx: EffectContext) -> list[str]:
        if self.g.ndim != 1 or self.g.size != ctx.dim or not np.all(np.isfinite(self.g)):
            return [f"Gravity: g must be a finite ({ctx.dim},) vector, got {self.g.tolist()}"]
        return []

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        state.gravity = self.g.copy()

    def force(self, s: FluidState) -> None:
        f = s.fluid
        s.force[f] += s.mass[f, None] * self.g
