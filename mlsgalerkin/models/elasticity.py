r"""Forms for small-strain isotropic linear elasticity (vector bases, ``n_components = dim``).

In 2D the 3D Lamé parameters give **plane strain**; ``lame_parameters(E, nu, plane_stress=True)``
returns the effective ``λ* = 2λμ/(λ + 2μ)`` for plane stress.

>>> lam, mu = lame_parameters(1.0, 0.25)
>>> round(lam, 12), round(mu, 12)
(0.4, 0.4)

Stress ``σ = 2μ ε + λ tr(ε) I``, strain ``ε = ½(∇u + ∇uᵀ)``. Units: ``E``, ``λ``, ``μ`` in Pa,
body force in N/m³ (force per unit volume).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

from mlsgalerkin.forms import BilinearForm, LinearForm
from mlsgalerkin.helpers import ddot, dot, eye, sym_grad, trace

__all__ = ["lame_parameters", "linear_stress", "stress", "linear_elasticity", "body_force"]


def lame_parameters(E: float, nu: float, *, plane_stress: bool = False) -> tuple[float, float]:
    """Lamé parameters ``(λ, μ)`` from Young's modulus ``E`` (Pa) and Poisson's ratio ``nu``."""
    E, nu = float(E), float(nu)
    if not E > 0:
        raise ValueError(f"Young's modulus must be positive, got {E}")
    if not -1.0 < nu < 0.5:
        raise ValueError(f"Poisson's ratio must lie in (-1, 0.5), got {nu}")
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    mu = E / (2.0 * (1.0 + nu))
    if plane_stress:
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return lam, mu


def linear_stress(lam: float = 1.0, mu: float = 1.0) -> Callable:
    """``C(ε) = 2μ ε + λ tr(ε) I`` acting on a ``(dim, dim, n)`` strain."""
    def C(eps):
        return 2.0 * mu * eps + lam * eye(trace(eps), eps.shape[0])
    return C


def stress(lam: float = 1.0, mu: float = 1.0) -> Callable:
    """``σ(u) = C(ε(u))`` of a displacement field: the flux for Nitsche's method."""
    C = linear_stress(lam, mu)

    def sigma(u):
        return C(sym_grad(u))
    return sigma


def linear_elasticity(lam: float = 1.0, mu: float = 1.0) -> BilinearForm:
    r"""``∫ σ(u) : ε(v) dΩ`` (plane strain in 2D with the 3D Lamé parameters)."""
    C = linear_stress(lam, mu)

    def weakform(u, v, w):
        return ddot(C(sym_grad(u)), sym_grad(v))
    weakform.__name__ = "linear_elasticity"
    return BilinearForm(weakform)


def body_force(b: ArrayLike | Callable) -> LinearForm:
    r"""``∫ b · v dΩ`` for a constant vector ``b`` ``(dim,)`` or a callable ``b(x) -> (dim, n)``."""
    if callable(b):
        def load(v, w):
            return dot(np.asarray(b(w.x), dtype=float), v)
    else:
        bb = np.asarray(b, dtype=float)
        if bb.ndim != 1:
            raise ValueError(f"constant body force must be a (dim,) vector, got shape {bb.shape}")

        def load(v, w):
            if v.shape[0] != bb.shape[0]:
                raise ValueError(f"body force has {bb.shape[0]} components, the basis {v.shape[0]}")
            return dot(bb[:, None], v)
    load.__name__ = "body_force"
    return LinearForm(load)
