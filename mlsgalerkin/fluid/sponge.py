r"""A damping (sponge) zone that absorbs waves at the end of a tank: the :class:`SpongeZone` effect.

A wave that reaches a tank's end wall reflects and returns. A floating body's heave then locks
onto the tank's sloshing period, and the reflection ends the window in which a wave maker's
waves can be compared with theory. A sponge zone damps the fluid's velocity towards rest over a
stretch of the tank in front of the wall, as a fictitious absorbing layer (Molteni, Grammauta &
Vitanza 2013; the "damping" zones of DualSPHysics and PySPH; open boundaries that absorb actively
are the alternative, Verbrugghe et al. 2019):

.. math::
    \mathbf f_i \mathrel{-}= m_i\,\sigma(\xi_i)\,(\mathbf v_i - \mathbf v_\infty),\qquad
    \sigma(\xi) = \sigma_{max}\,\xi^2,\qquad
    \xi_i = \mathrm{clip}\Big(\frac{(\mathbf x_i - \mathbf x_s)\cdot\mathbf e}{L},\ 0,\ 1\Big),

where the zone starts at ``start`` (the point ``x_s`` along the axis ``e``), reaches full
strength at ``start + length`` and continues beyond it; ``v_∞`` is the velocity the zone
relaxes to (rest by default). The quadratic ramp keeps the reflection from the zone's own
edge small.

How much comes back. In the zone a progressive wave's energy decays at the rate ``σ`` (its kinetic
energy is half of it), its amplitude over distance at ``σ/(2 c_g)`` (``c_g`` the group velocity);
what crosses the zone, meets the wall behind it and crosses back keeps
``exp(−σ_max L / (3 c_g))`` of its amplitude (for ``σ ≪ ω``). That is the floor of the
reflection coefficient; the rise of ``σ`` reflects a part of the wave itself, more as ``σ_max``
approaches the wave's angular frequency ``ω``. So a zone absorbs best when it is long (a
wavelength or more) and ``σ_max`` moderate (``σ_max L / (3 c_g)`` of 2 or more, ``σ_max`` below
``ω``). The wave maker measures its reflection coefficient by splitting three gauges' records
into incident and reflected waves (``mlsgalerkin.problems.wave_maker``,
``verification/wave_absorption.py``).

The damping is explicit: the time step is limited to ``Δt ≤ 1/σ_max`` (a relaxation of one
step at most). Inside the zone the flow is not physical; measure outside it.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from mlsgalerkin.fluid.effect import Effect, EffectContext, check_positive
from mlsgalerkin.fluid.state import FluidState

__all__ = ["SpongeZone", "sponge_rate"]


def sponge_rate(x: np.ndarray, start: float, length: float, axis: int, direction: float, rate: float) -> np.ndarray:
    """``σ(ξ) = rate · ξ²`` (1/s) at the positions ``x (n, d)``, ``ξ`` the clipped distance into
    the zone along ``axis`` (``direction`` +1: the zone lies beyond ``start``; −1: before it)."""
    xi = np.clip(direction * (x[:, axis] - start) / length, 0.0, 1.0)
    return rate * xi * xi


class SpongeZone(Effect):
    """Damps the fluid velocity towards ``velocity`` (default rest) in a zone along ``axis``
    (0: x, 1: y, 2: z) that starts at ``start`` (m) and reaches the full ``rate`` (1/s) at
    ``start + length`` (``length`` > 0: the zone lies beyond ``start``; < 0: before it, for the
    left end of a tank). Force ``f_i −= m_i σ(ξ_i)(v_i − v_∞)``, ``σ = rate · ξ²`` (module
    docstring). ``name`` tells two zones apart."""

    stages = ("force",)
    reads = ("mass",)

    def __init__(self, start: float, length: float, rate: float, *, axis: int = 0,
                 velocity: Sequence[float] | None = None, name: str = "sponge_zone") -> None:
        self.start, self.length, self.rate, self.axis = float(start), float(length), float(rate), int(axis)
        self.velocity = None if velocity is None else np.asarray(velocity, dtype=float)
        self.name = name
        self.power = 0.0   # the power the zone took out of the fluid at the last evaluation (W, per m in 2D)

    def __repr__(self) -> str:
        v = "" if self.velocity is None else f", velocity={self.velocity.tolist()}"
        return (f"SpongeZone(start={self.start:g}, length={self.length:g}, rate={self.rate:g}, "
                f"axis={self.axis}{v})")

    def check(self, ctx: EffectContext) -> list[str]:
        out: list[str] = []
        check_positive("SpongeZone", "rate", self.rate, out)
        if not (np.isfinite(self.length) and self.length != 0.0):
            out.append(f"SpongeZone: length must be a non-zero distance (m; negative for a zone before start), "
                       f"got {self.length!r}")
        if not (0 <= self.axis < ctx.dim):
            out.append(f"SpongeZone: axis must be 0 … {ctx.dim - 1} in {ctx.dim}D, got {self.axis}")
        if self.velocity is not None and self.velocity.shape != (ctx.dim,):
            out.append(f"SpongeZone: velocity must have {ctx.dim} components, got {self.velocity.tolist()}")
        return out

    def _sigma(self, s: FluidState) -> np.ndarray:
        direction = 1.0 if self.length > 0 else -1.0
        return sponge_rate(s.x[s.fluid], self.start, abs(self.length), self.axis, direction, self.rate)

    def force(self, s: FluidState) -> None:
        f = s.fluid
        sigma = self._sigma(s)
        rel = s.v[f] if self.velocity is None else s.v[f] - self.velocity
        damp = (s.mass[f] * sigma)[:, None] * rel
        s.force[f] -= damp
        self.power = float(np.einsum("id,id->", damp, s.v[f]))

    def time_step_limit(self, s: FluidState) -> float:
        return 1.0 / self.rate

    def summary(self) -> dict[str, Any]:
        return {"start_m": self.start, "length_m": self.length, "rate_per_s": self.rate, "axis": self.axis}
