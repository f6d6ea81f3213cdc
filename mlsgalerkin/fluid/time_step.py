r"""Every explicit time-step limit of the fluid, in one place; each returns seconds.

======================  ==================================================  ==================
limit                   formula (minimum over the fluid particles)          used by
======================  ==================================================  ==================
acoustic (CFL)          ``C h / (c + |v|)``, ``C = 0.4``                    ``TaitPressure``
viscous diffusion       ``C h² / ν_max``, ``ν = μ/ρ0``, ``C = 0.125``        ``NewtonianViscosity``
bulk viscosity          ``C h / (a_L c)``, ``C = 0.125`` (diffusion number   ``BulkViscosity``
                        of ``ν_b = a_L h c``)
pair viscosity          ``C h / (c + 0.6 (α c + β max φ))``, ``C = 0.4``     ``MonaghanViscosity``
                        (Monaghan 1992)
density diffusion       ``C h / (δ c0)``, ``C = 0.125``                     ``DensityDiffusion``
particle shifting       none (the shift is a fraction of the step's drift)  ``ParticleShifting``
force (acceleration)    ``C sqrt(min h / max |a|)``, ``C = 0.25``           the solver
======================  ==================================================  ==================

A limit that does not apply (no viscosity, zero acceleration, no particles) is ``inf``. The
solver takes the minimum over the limits of the listed effects and the force limit, times
``Scene.safety``, capped by ``Scene.dt_max``. The functions take the solver's own arrays and
do not validate them: a non-finite state gives a NaN limit, and the watchdog, which runs after
every step, names the particle and the quantity.

>>> import numpy as np
>>> h = np.full(3, 0.01)
>>> acoustic_limit(h, np.full(3, 20.0), np.zeros((3, 2)))
0.0002
>>> round(viscous_limit(h, np.full(3, 1e-6)), 12)
12.5
>>> round(pair_viscosity_limit(np.full(1, 0.012), np.full(1, 20.0), alpha=0.1, beta=0.0, max_phi=0.5), 12)
0.000226415094
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "acoustic_limit", "bulk_viscosity_limit", "density_diffusion_limit", "force_limit", "pair_viscosity_limit",
    "viscous_limit",
]

FloatArray = NDArray[np.float64]


def acoustic_limit(h: FloatArray, c: FloatArray, v: FloatArray, cfl: float = 0.4) -> float:
    """``cfl · min(h / (c + |v|))``: ``h, c (n,)`` (m, m/s), ``v (n, d)`` (m/s)."""
    if h.size == 0:
        return math.inf
    speed = c + np.sqrt(np.einsum("ij,ij->i", v, v))
    return cfl * float(np.min(h / speed))


def viscous_limit(h: FloatArray, nu: FloatArray, factor: float = 0.125) -> float:
    """``factor · min(h²) / max(ν)`` over ``h, ν (n,)`` (m, m²/s); ``inf`` when every ``ν`` is 0."""
    if not np.any(nu > 0):
        return math.inf
    return factor * float(np.min(h**2 / nu.max()))


def bulk_viscosity_limit(h: FloatArray, c: FloatArray, linear: float, factor: float = 0.125) -> float:
    """``factor · min(h / (a_L c))``: the diffusion limit of the linear bulk viscosity
    ``ν_b = a_L h c``; ``inf`` for ``a_L = 0``."""
    if linear <= 0 or h.size == 0:
        return math.inf
    return factor * float(np.min(h / (linear * c)))


def density_diffusion_limit(h: FloatArray, delta: float, c0: float, factor: float = 0.125) -> float:
    """``factor · min(h) / (δ c0)``: the diffusion limit of the δ-SPH density diffusion, whose
    coefficient is about ``δ h c0``; ``inf`` for ``δ = 0`` or no particles."""
    if delta <= 0 or h.size == 0:
        return math.inf
    return factor * float(np.min(h)) / (delta * c0)


def pair_viscosity_limit(h: FloatArray, c: FloatArray, alpha: float, beta: float, max_phi: float,
                         factor: float = 0.4) -> float:
    """Monaghan's viscous-acoustic limit ``factor · min(h / (c + 0.6 (α c + β max φ)))``
    (Monaghan 1992; ``λ = 0.4``); ``max_phi`` (m/s) from the last pair-viscosity evaluation."""
    if h.size == 0:
        return math.inf
    return float(factor * np.min(h / (c + 0.6 * (alpha * c + beta * float(max_phi)))))


def force_limit(h: FloatArray, a: FloatArray, factor: float = 0.25) -> float:
    """``factor · sqrt(min h / max |a|)`` for ``h (n,)`` (m), ``a (n, d)`` (m/s²); ``inf`` if
    every acceleration is zero."""
    amax = float(np.sqrt(np.max(np.einsum("ij,ij->i", a, a)))) if a.shape[0] else 0.0
    if not amax > 0:
        return math.inf
    return factor * math.sqrt(float(h.min()) / amax)
