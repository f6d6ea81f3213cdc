r"""Explicit time-step limits (seed digest §7.11); each returns a scalar in seconds.

======================  ===========================================  =======================
limit                   formula                                      default factor
======================  ===========================================  =======================
acoustic (CFL)          ``C h / (c + |v|)``, minimum over particles  ``C = 0.4``
viscous diffusion       ``C h² / ν``, ``ν = μ/ρ``                    ``C = 0.125``
force (acceleration)    ``C sqrt(h / |a|)``                          ``C = 0.25``
======================  ===========================================  =======================

A limit that does not apply (no viscosity, zero acceleration) is ``inf``; a solver takes the
minimum over the limits its effects supply, times a safety factor, capped by the user.

>>> import numpy as np
>>> acoustic_limit(h=0.01, c=20.0), round(viscous_limit(h=0.01, nu=1e-6), 12)
(0.0002, 12.5)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["acoustic_limit", "viscous_limit", "force_limit"]


def _positive(name: str, a: ArrayLike) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ValueError(f"{name} must be positive and finite")
    return a


def acoustic_limit(h: ArrayLike, c: ArrayLike, velocity: ArrayLike | None = None, factor: float = 0.4) -> float:
    """``factor * min(h / (c + |v|))``; ``velocity`` is ``(n, dim)`` or omitted."""
    h, c = _positive("h", h), _positive("c", c)
    speed = c if velocity is None else c + np.linalg.norm(np.atleast_2d(velocity), axis=-1)
    return float(factor * np.min(h / speed))


def viscous_limit(h: ArrayLike, nu: ArrayLike, factor: float = 0.125) -> float:
    """``factor * min(h² / ν)``; ``inf`` where ``ν = 0`` (inviscid)."""
    h = _positive("h", h)
    nu = np.asarray(nu, dtype=float)
    if np.any(nu < 0) or not np.all(np.isfinite(nu)):
        raise ValueError("kinematic viscosity nu must be non-negative and finite")
    with np.errstate(divide="ignore"):
        return float(factor * np.min(np.broadcast_to(h, np.broadcast(h, nu).shape) ** 2 / nu))


def force_limit(h: ArrayLike, acceleration: ArrayLike, factor: float = 0.25) -> float:
    """``factor * min(sqrt(h / |a|))``; ``acceleration`` ``(n, dim)`` in m/s²; ``inf`` if all zero."""
    h = _positive("h", h)
    a = np.linalg.norm(np.atleast_2d(np.asarray(acceleration, dtype=float)), axis=-1)
    if not np.all(np.isfinite(a)):
        k = int(np.flatnonzero(~np.isfinite(a))[0])
        raise ValueError(f"acceleration is not finite at particle {k}")
    with np.errstate(divide="ignore"):
        return float(factor * np.min(np.sqrt(h / a)))
